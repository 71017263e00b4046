#include "server/http/websocket_session.hpp"

#include <algorithm>

#include <boost/asio/post.hpp>

namespace rover::http {

namespace websocket = boost::beast::websocket;

// ---------------------------------------------------------------- WsConnectionImpl

void WsConnectionImpl::attach(std::weak_ptr<WebsocketSession> session) {
  std::lock_guard lock(mutex_);
  session_ = std::move(session);
}

void WsConnectionImpl::wake() {
  if (pending_.exchange(true)) return;  // a wake-up is already on its way: coalesce
  // The gate keeps stop() from tearing the io_context down while we post to it.
  std::shared_lock gate(state_->wakeGate());
  if (state_->stoppedLocked()) return;
  std::shared_ptr<WebsocketSession> session;
  {
    std::lock_guard lock(mutex_);
    session = session_.lock();
  }
  // Not attached yet: the session's first next() will see whatever prompted this call.
  if (!session) return;
  const net::any_io_executor ex = session->executor();
  try {
    // The strong reference moves into the handler, so the last one is dropped on the io thread.
    net::post(ex, [s = std::move(session)] { s->onWake(); });
  } catch (...) {
    // Out of memory while posting: nothing sensible to do from the planner's thread.
  }
}

// ---------------------------------------------------------------- admission

std::optional<Response> admitSubscriber(ServerState& state, const std::string& path, std::shared_ptr<void>& place) {
  std::string refusal;
  place = state.websockets->admit(path, state.config.maxStreamSubscribers, state.config.maxSubscribers, refusal);
  if (place) return std::nullopt;
  Response r = Response::error(503, "too_many_subscribers", refusal, "");
  r.headers.emplace_back("Retry-After", "5");
  return r;
}

// ---------------------------------------------------------------- WebsocketSession

WebsocketSession::WebsocketSession(beast::tcp_stream&& stream, std::shared_ptr<ServerState> state,
                                   std::shared_ptr<WsConnectionImpl> connection,
                                   std::shared_ptr<WsSource> source, std::string path,
                                   std::shared_ptr<void> place)
    : ws_(std::move(stream)),
      executor_(ws_.get_executor()),
      state_(std::move(state)),
      connection_(std::move(connection)),
      source_(std::move(source)),
      path_(std::move(path)),
      place_(std::move(place)),
      pace_(executor_),
      writeTimer_(executor_) {}

WebsocketSession::~WebsocketSession() {
  if (id_) state_->remove(*id_);
}

void WebsocketSession::run(bhttp::request<bhttp::empty_body> request) {
  request_ = std::move(request);
  id_ = state_->add(weak_from_this());
  if (!id_) {
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
    return;
  }
  connection_->attach(weak_from_this());

  beast::get_lowest_layer(ws_).expires_never();  // the websocket stream has its own timeouts
  configureServerWebsocket(ws_, state_->config);
  ws_.async_accept(request_,
                   beast::bind_front_handler(&WebsocketSession::onAccept, shared_from_this()));
}

void WebsocketSession::close() {
  net::post(executor_, [self = shared_from_this()] {
    self->pace_.cancel();
    self->writeTimer_.cancel();
    beast::error_code ec;
    beast::get_lowest_layer(self->ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(self->ws_).socket().close(ec);
  });
}

void WebsocketSession::onAccept(beast::error_code ec) {
  if (ec) return finish("handshake failed: " + ec.message());
  open_ = true;
  opened_ = std::chrono::steady_clock::now();
  if (state_->config.logRequests) state_->log("WS " + path_ + " 101 open");
  readLoop();
  pull();
}

void WebsocketSession::readLoop() {
  ws_.async_read_some(readBuffer_, 16 * 1024,
                      beast::bind_front_handler(&WebsocketSession::onRead, shared_from_this()));
}

void WebsocketSession::onRead(beast::error_code ec, std::size_t bytes) {
  if (ec) {
    // The client closed, the socket failed, or stop(): this ends the session (writes, the pace
    // timer and the parked state all stop holding it once their handlers return).
    return finish(ec == websocket::error::closed ? "closed" : ec.message());
  }
  messageBytes_ += bytes;
  if (messageBytes_ > kMaxClientMessageBytes) {
    // No further read: the close handshake reads (and drops) the rest up to the close reply.
    readBuffer_.consume(readBuffer_.size());
    if (state_->config.logRequests) state_->log("WS " + path_ + " client message over the limit: closing (1009)");
    return closeWith(websocket::close_code::too_big);
  }
  // A text message is handed to the source whole (bounded above); binary ones are dropped.
  if (ws_.got_text()) message_.append(static_cast<const char*>(readBuffer_.data().data()), readBuffer_.size());
  readBuffer_.consume(readBuffer_.size());
  if (ws_.is_message_done()) {
    messageBytes_ = 0;
    std::string text = std::move(message_);
    message_.clear();
    if (!text.empty() && !finished_) {
      try {
        source_->onMessage(text);
      } catch (const std::exception& e) {
        if (state_->config.logRequests) state_->log("WS " + path_ + " message refused: " + e.what());
      }
    }
  }
  readLoop();
}

void WebsocketSession::onWake() {
  if (waiting_) pull();  // otherwise a write or the pace timer will pull anyway
}

void WebsocketSession::pull() {
  if (!open_ || writing_ || pacing_ || closing_) return;
  waiting_ = false;
  connection_->clearPending();
  std::optional<WsFrame> frame;
  try {
    frame = source_->next();
  } catch (const std::exception& e) {
    if (state_->config.logRequests) state_->log("WS " + path_ + " source failed: " + e.what());
    return closeWith(websocket::close_code::internal_error);
  } catch (...) {
    return closeWith(websocket::close_code::internal_error);
  }
  if (!frame) {
    waiting_ = true;
    return;
  }
  frame_ = std::move(*frame);
  writing_ = true;
  // A subscriber that stops reading must not hold its frame and socket forever: one write gets
  // readTimeout + 1 s per 256 KiB, then the connection is dropped.
  writeTimer_.expires_after(state_->config.readTimeout +
                            std::chrono::seconds(frame_.data.size() / (256 * 1024)));
  writeTimer_.async_wait(beast::bind_front_handler(&WebsocketSession::onWriteTimer, shared_from_this()));
  ws_.binary(frame_.binary);
  ws_.async_write(net::buffer(frame_.bytes()),
                  beast::bind_front_handler(&WebsocketSession::onWrite, shared_from_this()));
}

void WebsocketSession::onWriteTimer(beast::error_code ec) {
  if (ec || !writing_) return;  // the write completed (or the session ended) first
  // A close frame cannot reach a peer that does not read: tear the connection down instead.
  if (state_->config.logRequests)
    state_->log("WS " + path_ + " dropping a subscriber that does not read (" +
                std::to_string(frame_.data.size()) + " bytes pending)");
  droppedSlow_ = true;
  beast::error_code ignored;
  beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
  beast::get_lowest_layer(ws_).socket().close(ignored);
}

void WebsocketSession::onWrite(beast::error_code ec, std::size_t bytes) {
  writing_ = false;
  writeTimer_.cancel();
  if (ec) return finish(droppedSlow_ ? "dropped: the client does not read" : "write failed: " + ec.message());
  ++frames_;
  bytes_ += bytes;
  frame_.data = std::string();  // release the frame's memory while parked
  frame_.shared.reset();
  if (frame_.last) return closeWith(websocket::close_code::normal);
  std::chrono::milliseconds interval{0};
  try {
    interval = source_->minInterval();
  } catch (...) {
  }
  if (interval.count() <= 0) return pull();
  pacing_ = true;
  pace_.expires_after(interval);
  pace_.async_wait(beast::bind_front_handler(&WebsocketSession::onPaced, shared_from_this()));
}

void WebsocketSession::onPaced(beast::error_code ec) {
  pacing_ = false;
  if (ec) return;  // cancelled by close()
  pull();
}

void WebsocketSession::closeWith(websocket::close_code code) {
  if (closing_ || !open_) return;
  closing_ = true;
  pace_.cancel();
  // The close handshake is bounded by Beast's handshake timeout: kCloseReplyWait from here.
  auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::server);
  timeouts.handshake_timeout = kCloseReplyWait;
  timeouts.idle_timeout = websocket::stream_base::none();
  ws_.set_option(timeouts);
  ws_.async_close(code, beast::bind_front_handler(&WebsocketSession::onClose, shared_from_this()));
}

void WebsocketSession::onClose(beast::error_code ec) {
  // Beast has read the client's close reply (or given up waiting) and shut the connection down.
  if (ec) {
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }
  finish(ec ? "close: " + ec.message() : "closed by the server");
}

void WebsocketSession::finish(const std::string& why) {
  if (finished_) return;
  finished_ = true;
  open_ = false;
  pace_.cancel();
  writeTimer_.cancel();
  if (state_->config.logRequests) {
    const auto ms = opened_.time_since_epoch().count() == 0
                        ? 0
                        : std::chrono::duration_cast<std::chrono::milliseconds>(
                              std::chrono::steady_clock::now() - opened_)
                              .count();
    state_->log("WS " + path_ + " close " + std::to_string(frames_) + " frames " +
                std::to_string(bytes_) + " bytes " + std::to_string(ms) + " ms (" + why + ")");
  }
}

}  // namespace rover::http
