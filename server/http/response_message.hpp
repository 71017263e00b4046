#pragma once
// A Response as the Beast message a session writes (Beast advanced server's response writers,
// apart from the I/O loop): status line, the server's own headers and CORS, a body from memory or
// from a file on disk, and what a HEAD request leaves out. No socket here: the session writes the
// message it gets.
#include <cstdint>
#include <memory>
#include <variant>

#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/file_body.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include "server/http/http_server.hpp"
#include "server/http/http_types.hpp"

namespace rover::http {

// What the request asked of the answer's framing.
struct ResponseFraming {
  unsigned version = 11;   // HTTP/1.x of the request
  bool keepAlive = false;  // the connection carries another request afterwards
  bool head = false;       // a HEAD request: headers only
};

// The message to write, the status its log line reports and the body bytes it carries.
struct ResponseMessage {
  std::variant<std::shared_ptr<boost::beast::http::response<boost::beast::http::empty_body>>,
               std::shared_ptr<boost::beast::http::response<boost::beast::http::string_body>>,
               std::shared_ptr<boost::beast::http::response<boost::beast::http::file_body>>>
      message;
  int status = 0;
  std::uint64_t bytes = 0;  // 0 for HEAD
};

// 1xx, 204 and 304 carry no body (RFC 9110 §6.4.1).
bool bodyless(int status);

// `res` as a message; a response file that cannot be opened (removed meanwhile) becomes 404.
ResponseMessage responseMessage(Response res, const ResponseFraming& framing, const ServerConfig& config);

}  // namespace rover::http
