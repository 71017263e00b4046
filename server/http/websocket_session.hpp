#pragma once
// One WebSocket connection, fed by a WsSource in a pull loop: one write in flight; after each
// write (and initially) the session asks the source for the next frame; "nothing now" parks it
// until WsConnection::wake(). Frames that are not `last` are spaced by
// source->minInterval() (the wait happens before next(), so the frame written is the freshest
// state). A read loop hands whole text messages to source->onMessage (the event stream's
// presence; other sources ignore them) and notices closes. Only wake() runs on other
// threads.
//
// Closing (issue 22): every close the server starts — the last frame, a source failure, a client
// message over kMaxClientMessageBytes (1009) — is Beast's close handshake: the close frame, then
// the client's messages are read and dropped until its close reply (at most kCloseReplyWait), and
// only then is the TCP connection shut down. Closing a socket with unread bytes makes the kernel
// send a reset, which can destroy the close frame before the client reads it; so the session
// counts message sizes itself instead of letting Beast fail the connection (Beast tears it down
// right after its close frame). A client that stops reading is not sent a close frame: its
// connection is torn down when a write misses its deadline.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <boost/asio/steady_timer.hpp>
#include <boost/beast/websocket.hpp>

#include "server/http/http_session.hpp"

namespace rover::http {

class WebsocketSession;

// The largest client message read (the server discards client messages; a bigger one is closed
// with 1009). No permessage-deflate: no compression bombs.
constexpr std::size_t kMaxClientMessageBytes = 64 * 1024;
// How long a close the server started waits for the client's close reply.
constexpr std::chrono::seconds kCloseReplyWait{2};

// The options every server-side WebSocket gets (also used by tests/fuzz/fuzz_websocket_frame.cpp
// so the fuzzer parses frames exactly as configured here).
template <class NextLayer>
void configureServerWebsocket(boost::beast::websocket::stream<NextLayer>& ws, const ServerConfig& config) {
  namespace websocket = boost::beast::websocket;
  auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::server);
  timeouts.handshake_timeout = config.readTimeout;
  // Idle pings: a peer that stops answering (or reading) is dropped after this long.
  timeouts.idle_timeout = std::max<std::chrono::steady_clock::duration>(config.readTimeout * 2,
                                                                        std::chrono::seconds(20));
  timeouts.keep_alive_pings = true;
  ws.set_option(timeouts);
  ws.set_option(websocket::stream_base::decorator(
      [](websocket::response_type& res) { res.set(bhttp::field::server, "roverplan"); }));
  // No size limit in Beast: WebsocketSession reads in pieces and closes a message over
  // kMaxClientMessageBytes itself (with the close handshake, see above).
  ws.read_message_max(0);
  // A message goes out as one frame (one gathered write), not as 4 KiB fragments each with a
  // write and a completion: a 1.8 MB grid to 1000 subscribers is 1000 writes, not 450 000.
  ws.auto_fragment(false);
}

// Takes a place for an upgrade of `path` under config.maxStreamSubscribers / maxSubscribers; the
// 503 (with Retry-After) to answer when there is none.
std::optional<Response> admitSubscriber(ServerState& state, const std::string& path, std::shared_ptr<void>& place);

// The handle given to the WsHandler. Holds the session only weakly: it stays safe to call after
// the session or the whole server is gone (wake() is then a no-op), and wake() never keeps a
// session alive on the caller's thread (the strong reference travels inside the posted handler).
class WsConnectionImpl : public WsConnection {
 public:
  explicit WsConnectionImpl(std::shared_ptr<ServerState> state) : state_(std::move(state)) {}
  void wake() override;

  void attach(std::weak_ptr<WebsocketSession> session);
  // Called on the strand right before source->next(): a wake() after this posts again.
  void clearPending() { pending_.store(false); }

 private:
  std::shared_ptr<ServerState> state_;
  std::atomic<bool> pending_{false};
  std::mutex mutex_;
  std::weak_ptr<WebsocketSession> session_;
};

class WebsocketSession : public Closable, public std::enable_shared_from_this<WebsocketSession> {
 public:
  WebsocketSession(beast::tcp_stream&& stream, std::shared_ptr<ServerState> state,
                   std::shared_ptr<WsConnectionImpl> connection, std::shared_ptr<WsSource> source,
                   std::string path, std::shared_ptr<void> place);
  ~WebsocketSession() override;

  // Accepts the upgrade `request` (already routed and authorised), then starts both loops.
  void run(bhttp::request<bhttp::empty_body> request);
  void close() override;
  const net::any_io_executor& executor() const { return executor_; }
  void onWake();  // on the strand

 private:
  void onAccept(beast::error_code ec);
  void readLoop();
  void onRead(beast::error_code ec, std::size_t bytes);
  void pull();
  void onWrite(beast::error_code ec, std::size_t bytes);
  void onPaced(beast::error_code ec);
  void onWriteTimer(beast::error_code ec);
  void closeWith(beast::websocket::close_code code);
  void onClose(beast::error_code ec);
  void finish(const std::string& why);

  beast::websocket::stream<beast::tcp_stream> ws_;
  const net::any_io_executor executor_;
  std::shared_ptr<ServerState> state_;
  std::shared_ptr<WsConnectionImpl> connection_;
  std::shared_ptr<WsSource> source_;
  const std::string path_;
  std::shared_ptr<void> place_;  // under the subscriber limits (admitSubscriber)
  std::optional<std::uint64_t> id_;
  net::steady_timer pace_;
  net::steady_timer writeTimer_;  // the deadline of the write in flight
  beast::flat_buffer readBuffer_;
  bhttp::request<bhttp::empty_body> request_;

  WsFrame frame_;      // the frame being written
  bool open_ = false;  // accepted and not yet closed/failed
  bool writing_ = false;
  bool pacing_ = false;
  bool waiting_ = false;  // next() said "nothing now": parked until wake()
  bool closing_ = false;
  bool finished_ = false;
  bool droppedSlow_ = false;
  std::size_t messageBytes_ = 0;  // of the client message being read
  std::string message_;           // its text so far (source->onMessage)
  std::uint64_t frames_ = 0;
  std::uint64_t bytes_ = 0;
  std::chrono::steady_clock::time_point opened_;
};

}  // namespace rover::http
