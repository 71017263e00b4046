#include "server/http/dispatch.hpp"

#include <algorithm>
#include <fstream>
#include <string_view>

#include <boost/beast/websocket/rfc6455.hpp>

#include "server/api/error_table.hpp"
#include "server/http/request_framing.hpp"

namespace rover::http {

namespace bhttp = boost::beast::http;

namespace {

// Beast 1.74 speaks boost::string_view.
std::string_view sv(boost::beast::string_view s) {
  return {s.data(), s.size()};
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool isApiPath(const std::string& path) {
  return path == "/api" || path.rfind("/api/", 0) == 0;
}

// The path of a target that could not be parsed, for the log line only (bounded, no query).
std::string rawPath(std::string_view target) {
  return std::string(target.substr(0, std::min<std::size_t>(target.find('?'), 200)));
}

Response preflight() {
  Response r;
  r.status = 204;
  r.contentType.clear();
  r.headers = {{"Access-Control-Allow-Methods", "GET, POST, PUT, PATCH, DELETE, OPTIONS"},
               {"Access-Control-Allow-Headers", "Authorization, Content-Type"},
               {"Access-Control-Max-Age", "600"}};
  return r;
}

// The answer for the exception in flight (call inside a catch); a 500's detail is logged.
Response failed(const Request& req, const ServerState& state, const char* what) noexcept {
  try {
    api::ErrorAnswer a = api::errorAnswer(std::current_exception());
    if (!a.logDetail.empty()) state.log("http: " + req.method + " " + req.path + ": " + what + ": " + a.logDetail);
    return std::move(a.response);
  } catch (...) {  // building the answer itself failed (out of memory)
    Response r;
    r.status = 500;
    r.body = R"({"error":{"code":"internal","message":"internal error"}})";
    return r;
  }
}

// For no route: a WebSocket-only path (426), a static file, another method's path (405), or 404.
Response unrouted(const ServerState& state, const Request& req, bhttp::verb method, bool isUpgrade,
                  bool pathKnown) {
  const std::string& path = req.path;
  if (method == bhttp::verb::get && !isUpgrade) {
    Router::Match ws = state.router.match("GET", path, true);
    if (ws.route && ws.route->method == "WS")
      return Response::error(426, "upgrade_required", "this path is a WebSocket endpoint", "upgrade");
  }
  if (!isApiPath(path) && state.statics.enabled() && (method == bhttp::verb::get || method == bhttp::verb::head))
    return state.statics.serve(path);
  if (pathKnown) {
    std::string allow;
    for (const auto& m : state.router.allowedMethods(path)) allow += (allow.empty() ? "" : ", ") + m;
    Response r = Response::error(405, "method_not_allowed", req.method + " is not allowed on " + path, "method");
    r.headers.emplace_back("Allow", allow);
    return r;
  }
  return Response::error(404, "not_found", "no route for " + req.method + " " + path, "path");
}

}  // namespace

Routing routeHead(const ServerState& state, const bhttp::request_header<>& head, Request& req) {
  req.method = std::string(head.method_string());
  if (auto bad = checkFraming(head)) {
    // The rest of the connection's bytes cannot be trusted to be framed as the client meant:
    // answer and close, never parse them as another request.
    req.path = rawPath(sv(head.target()));
    return {Response::error(bad->status, bad->code, bad->message, bad->field), true, nullptr};
  }
  for (const auto& field : head) {
    std::string name = lower(sv(field.name_string()));
    auto [it, inserted] = req.headers.emplace(name, std::string(field.value()));
    if (!inserted) it->second += ", " + std::string(field.value());
  }
  if (std::string repeated; !parseTarget(sv(head.target()), req.path, req.query, &repeated)) {
    req.path = rawPath(sv(head.target()));
    if (!repeated.empty())
      return {Response::error(400, "invalid_parameter", "the query parameter " + repeated + " is given more than once",
                              repeated),
              false, nullptr};
    return {Response::error(400, "bad_request", "invalid request target", "path"), false, nullptr};
  }

  const ServerConfig& cfg = state.config;
  const bhttp::verb method = head.method();
  const bool isUpgrade = boost::beast::websocket::is_upgrade(head);
  const bool safeMethod = method == bhttp::verb::get || method == bhttp::verb::head || method == bhttp::verb::options;
  if (auto refused = refuseByOrigin(state.origins, req, head.version(), isUpgrade || !safeMethod))
    return {std::move(refused), false, nullptr};
  if (!cfg.corsOrigin.empty() && method == bhttp::verb::options) return {preflight(), false, nullptr};

  Router::Match m = state.router.match(req.method, req.path, isUpgrade);
  const bool wsRoute = m.route && m.route->method == "WS";
  const bool authOn = !cfg.token.empty() || !cfg.namedTokens.empty();
  const bool needAuth = authOn && (m.route ? m.route->options.requireAuth : isApiPath(req.path));
  if (needAuth) {
    if (!cfg.namedTokens.empty()) {
      auto name = bearerName(req, cfg.namedTokens, wsRoute);
      if (!name) return {unauthorized(), false, nullptr};
      req.operatorName = std::move(*name);
      req.operatorFromToken = !req.operatorName.empty();
    } else if (!bearerAuthorized(req, cfg.token, wsRoute)) {
      return {unauthorized(), false, nullptr};
    }
  }
  // A token's name says who it is; without one, the client may say so itself.
  if (req.operatorName.empty() && req.headers.count("x-operator")) {
    auto name = validOperatorName(req.header("x-operator"));
    if (!name)
      return {Response::error(400, "invalid_header",
                              "X-Operator must be at most " + std::to_string(kMaxOperatorChars) +
                                  " printable characters (UTF-8, no control characters)",
                              "X-Operator"),
              false, nullptr};
    req.operatorName = std::move(*name);
  }
  if (!m.route) return {unrouted(state, req, method, isUpgrade, m.pathKnown), false, nullptr};
  req.params = std::move(m.params);
  return {std::nullopt, false, m.route};
}

Response invoke(const Route& route, const Request& req, const ServerState& state) noexcept {
  try {
    return route.handler(req);
  } catch (...) {
    return failed(req, state, "handler failed");
  }
}

std::optional<Response> tryQuick(const Route& route, const Request& req, const ServerState& state) noexcept {
  if (!route.options.blocking || !route.options.quick) return std::nullopt;
  try {
    return route.options.quick(req);
  } catch (...) {
    return failed(req, state, "quick answer failed");
  }
}

std::variant<std::shared_ptr<WsSource>, Response> openStream(const Route& route, const Request& req,
                                                            std::shared_ptr<WsConnection> connection,
                                                            const ServerState& state) noexcept {
  try {
    std::shared_ptr<WsSource> source = route.wsHandler(req, std::move(connection));
    if (source) return source;
    return Response::error(500, "internal", "the WebSocket handler returned no source");
  } catch (const std::exception& e) {
    Response r = failed(req, state, "WebSocket handler failed");
    // An upgrade's failure has always shown its text (the stream handlers' messages hold no paths).
    if (r.status == 500) r = Response::error(500, "internal", e.what());
    return r;
  } catch (...) {
    return failed(req, state, "WebSocket handler failed");
  }
}

Response dispatch(ServerState& state, const bhttp::request<bhttp::string_body>& message) {
  Request req;
  Routing routing = routeHead(state, message.base(), req);
  if (routing.answer) return std::move(*routing.answer);
  const Route& route = *routing.route;
  if (route.method == "WS")
    return Response::error(426, "upgrade_required", "this path is a WebSocket endpoint", "upgrade");
  const bool stream = route.options.streamBody;
  const std::uint64_t limit = stream ? state.config.maxUploadBytes : state.config.maxBodyBytes;
  if (auto refused = checkBodyLength(message.body().size(), limit))
    return Response::error(refused->status, refused->code, refused->message, refused->field);
  TempFile body;
  if (stream) {
    body.adopt(state.uploads.newPath());
    std::ofstream(body.path(), std::ios::binary) << message.body();
    req.bodyFile = body.path();
  } else {
    req.body = message.body();
  }
  req.bodySize = message.body().size();
  if (auto quick = tryQuick(route, req, state)) return std::move(*quick);
  return invoke(route, req, state);
}

}  // namespace rover::http
