#pragma once
// What route handlers see and return: a transport-neutral request/response, so handlers are plain
// functions testable without sockets. The Beast sessions (http_session, websocket_session) convert.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rover::http {

struct Request {
  std::string method;                          // "GET", "POST", ...
  std::string path;                            // percent-decoded, without the query
  std::map<std::string, std::string> query;    // percent-decoded
  std::map<std::string, std::string> headers;  // names lower-case
  std::map<std::string, std::string> params;   // captures of the route pattern, e.g. {id}
  std::string body;                            // in-memory body (JSON routes)
  std::string bodyFile;  // streamed routes: the body on disk (deleted after the handler returns)
  std::uint64_t bodySize = 0;
  std::string remote;  // peer address
  // Who sends it (issue 26): the name of the bearer token (--token-file "name:token" lines), else
  // the X-Operator header (validated by dispatch), else "". Events and history say `by` with it.
  std::string operatorName;
  bool operatorFromToken = false;  // operatorName is a named token's: the client cannot rename itself
  std::string header(const std::string& lowerName) const;
};

struct Response {
  int status = 200;
  std::string contentType = "application/json";
  std::string body;
  std::string file;  // when set, the response body is this file (sent from disk)
  std::vector<std::pair<std::string, std::string>> headers;

  static Response json(int status, const nlohmann::json& j);
  // {"error": {"code", "message", "field"}} (DESIGN.md conventions).
  static Response error(int status, const std::string& code, const std::string& message,
                        const std::string& field = "");
};

// Thrown by handlers for an expected failure; the server answers Response::error(...).
class ApiError : public std::runtime_error {
 public:
  ApiError(int status, std::string code, const std::string& message, std::string field = "")
      : std::runtime_error(message),
        status_(status),
        code_(std::move(code)),
        field_(std::move(field)) {}
  int status() const { return status_; }
  const std::string& code() const { return code_; }
  const std::string& field() const { return field_; }
  // Extra response headers, e.g. Retry-After on a 429.
  ApiError& withHeader(std::string name, std::string value) {
    headers_.emplace_back(std::move(name), std::move(value));
    return *this;
  }
  const std::vector<std::pair<std::string, std::string>>& headers() const { return headers_; }
  // Extra members of the error object, e.g. "current" (the stored object) on a 412.
  ApiError& withDetail(const std::string& key, nlohmann::json value) {
    details_[key] = std::move(value);
    return *this;
  }
  const nlohmann::json& details() const { return details_; }

 private:
  nlohmann::json details_ = nlohmann::json::object();
  int status_;
  std::string code_;
  std::string field_;
  std::vector<std::pair<std::string, std::string>> headers_;
};

using Handler = std::function<Response(const Request&)>;
// A blocking route's answer from what is at hand, tried on the io thread before the request goes
// to the work pool (RouteOptions::quick); nullopt: "not at hand", the pool runs the handler.
using QuickHandler = std::function<std::optional<Response>(const Request&)>;

// --- WebSocket: a pull model. The session asks its source for the next frame whenever it may
// write (one write in flight); the source says "nothing now" and later calls wake() on the
// connection. So a slow client costs a cursor, never a queue, and intermediate state coalesces.
struct WsFrame {
  WsFrame() = default;
  WsFrame(bool isBinary, std::string bytes, bool isLast = false)
      : binary(isBinary), data(std::move(bytes)), last(isLast) {}
  // One immutable buffer shared by many clients (e.g. a snapshot): no copy per client.
  WsFrame(bool isBinary, std::shared_ptr<const std::string> bytes, bool isLast = false)
      : binary(isBinary), last(isLast), shared(std::move(bytes)) {}

  bool binary = false;
  std::string data;
  bool last = false;  // close the socket (normal closure) after this frame
  std::shared_ptr<const std::string> shared;  // when set, sent instead of `data`
  const std::string& bytes() const { return shared ? *shared : data; }
};

class WsConnection {
 public:
  virtual ~WsConnection() = default;
  // Thread-safe; cheap when called often (coalesced into one wake-up).
  virtual void wake() = 0;
};

class WsSource {
 public:
  virtual ~WsSource() = default;
  virtual std::optional<WsFrame> next() = 0;
  // Minimum spacing of frames that are not `last`, so a fast planner does not flood a browser.
  virtual std::chrono::milliseconds minInterval() const { return std::chrono::milliseconds(30); }
  // A whole text message from the client (at most kMaxClientMessageBytes); ignored by default.
  // Called on the session's strand, never at the same time as next().
  virtual void onMessage(const std::string& /*text*/) {}
};

// Builds the source for an upgrade request (may throw ApiError: answered as HTTP, no upgrade).
using WsHandler =
    std::function<std::shared_ptr<WsSource>(const Request&, std::shared_ptr<WsConnection>)>;

}  // namespace rover::http
