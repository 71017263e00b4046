#pragma once
// One HTTP/1.1 connection (keep-alive, one request at a time). Reads the header first (one
// deadline for all of it), checks its framing, then picks the body type by route: a file on disk
// for streamed uploads, a string otherwise; the body is read under a bytes-per-second floor
// (RateFloor). Runs the handler on the connection's strand, or on the work pool for blocking
// routes (the response is posted back to the strand), writes the response, and hands WebSocket
// upgrades over to a WebsocketSession. The session feeds Beast's parser itself, so every parser
// exception is caught here: no exception leaves a session's handler (it is logged and the
// connection closed). What to answer is decided in dispatch.hpp; this file only moves bytes.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include <boost/asio/steady_timer.hpp>

#include "server/http/rate_floor.hpp"
#include "server/http/server_state.hpp"

namespace rover::http {

namespace beast = boost::beast;
namespace bhttp = boost::beast::http;
namespace net = boost::asio;
using tcp = boost::asio::ip::tcp;

class HttpSession : public Closable, public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, std::shared_ptr<ServerState> state);
  ~HttpSession() override;
  void run();
  void close() override;

 private:
  enum class Stage { Header, Body };

  void readHeader();
  // Feeds the buffered bytes to the current parser; reads more while it needs them.
  void parse();
  void onRead(beast::error_code ec, std::size_t bytes);
  void onParseError(beast::error_code ec);
  void onHeader();
  void readBody();
  void onContinueWritten(beast::error_code ec, std::size_t bytes);
  void startBodyRead();
  void armRateTimer();
  void onRateTimer(beast::error_code ec);
  void stopRateTimer();
  void onBody();
  void runOnPool();
  void respond(Response res);  // after the handler: drop the body file, send
  void upgrade();

  // Writes `res` (JSON, string or file); `close` ends the connection afterwards.
  void send(Response res, bool close = false);
  void sendError(int status, const std::string& code, const std::string& message,
                 const std::string& field, bool close = false);
  template <class Message>
  void write(std::shared_ptr<Message> msg, int status, std::uint64_t bytes, bool close);
  void onWrite(beast::error_code ec, std::size_t bytes);
  // Shuts down our side and drains what the peer still sends (bounded), so the peer reads the
  // response instead of a reset when we close on an unread body.
  void lingeringClose();
  void onDrain(beast::error_code ec, std::size_t bytes);
  void closeNow();  // closes the socket and stops the rate timer
  void removeTempFile();
  void unregister();

  // A completion handler of this session that catches whatever it throws: logged, and the
  // connection is closed (nothing may escape into the io loop).
  template <class... Args>
  auto guarded(void (HttpSession::*fn)(Args...));
  void abort(const char* what) noexcept;

  beast::tcp_stream stream_;
  const net::any_io_executor executor_;
  std::shared_ptr<ServerState> state_;
  std::optional<std::uint64_t> id_;
  bool handedOff_ = false;  // stream_ moved into a WebsocketSession
  beast::flat_buffer buffer_;

  // The current request.
  Stage stage_ = Stage::Header;
  std::optional<bhttp::request_parser<bhttp::empty_body>> headerParser_;
  std::optional<bhttp::request_parser<bhttp::string_body>> stringParser_;
  std::optional<bhttp::request_parser<bhttp::file_body>> fileParser_;
  Request request_;
  const Route* route_ = nullptr;
  TempFile tempFile_;  // the streamed body
  bool keepAlive_ = false;
  bool head_ = false;
  unsigned version_ = 11;
  std::chrono::steady_clock::time_point started_;
  std::string remote_;

  // The body's progress deadline (a timer of its own, so a too-slow body is answered 408
  // rather than cut silently by the stream's timeout).
  RateFloor rate_;
  net::steady_timer rateTimer_;
  bool rateTimerArmed_ = false;
  bool watchingBody_ = false;
  bool tooSlow_ = false;

  // The response being written (one write in flight) and what the log line reports.
  std::shared_ptr<void> response_;
  bool closeAfterWrite_ = false;
  int logStatus_ = 0;
  std::uint64_t logBytes_ = 0;
  std::shared_ptr<bhttp::response<bhttp::empty_body>> continue_;
  char drain_[4096];
};

}  // namespace rover::http
