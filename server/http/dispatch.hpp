#pragma once
// What the server answers, apart from the socket (Beast advanced server's handle_request): the
// session reads bytes and writes responses; these functions decide. A request header is routed
// first (it may be answered before its body is read: a refusal, a preflight, a static file, a
// 404); a routed request with its body is then handed to its handler, and whatever the handler
// throws is answered through the error table (server/api/error_table.hpp). dispatch() runs both on
// a request held in memory, so tests drive the whole decision without a socket.
#include <memory>
#include <optional>
#include <variant>

#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include "server/http/server_state.hpp"

namespace rover::http {

// The outcome of a request header.
struct Routing {
  std::optional<Response> answer;  // answered now: the body, if any, is not read
  bool close = false;              // with `answer`: the connection cannot carry another request
  const Route* route = nullptr;    // otherwise: the route to read the body for
};

// Fills `req` from `head` (method, lower-cased header names with repeats joined, the
// percent-decoded path and query, the route's captures) and decides, in this order: framing (400
// and close), the target (400), Host and Origin (request_origin.hpp), a CORS preflight (204), the
// route, the bearer token (401), and for no route 426 (a WebSocket path), a static file, 405 with
// Allow, or 404.
Routing routeHead(const ServerState& state, const boost::beast::http::request_header<>& head, Request& req);

// The handler's answer; never throws (a failure is answered through the error table, and a 500's
// detail goes to the server's log).
Response invoke(const Route& route, const Request& req, const ServerState& state) noexcept;

// A blocking route's quick answer (RouteOptions::quick) on the calling io thread, or nullopt
// when it has none or none at hand; never throws (a failure is answered like invoke's).
std::optional<Response> tryQuick(const Route& route, const Request& req, const ServerState& state) noexcept;

// The route's WebSocket source for an upgrade, or the answer refusing it (what its handler threw).
std::variant<std::shared_ptr<WsSource>, Response> openStream(const Route& route, const Request& req,
                                                            std::shared_ptr<WsConnection> connection,
                                                            const ServerState& state) noexcept;

// routeHead + invoke for a whole request held in memory: what a session answers it, without the
// socket, the work pool (a blocking handler's quick answer is tried, then the handler runs here) or an upgrade (a WebSocket route, which
// needs a connection, is answered 426 upgrade_required). A streamed-body route gets the body in a
// temporary file, removed afterwards.
Response dispatch(ServerState& state, const boost::beast::http::request<boost::beast::http::string_body>& message);

}  // namespace rover::http
