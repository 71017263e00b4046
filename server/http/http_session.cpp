#include "server/http/http_session.hpp"

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <variant>

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>

#include "server/http/dispatch.hpp"
#include "server/http/request_framing.hpp"
#include "server/http/response_message.hpp"
#include "server/http/websocket_session.hpp"

namespace rover::http {

namespace fs = std::filesystem;

namespace {

// A write of the streamed body failed because the disk (or the file size limit) is full: the
// client gets 507, not a reset (Beast's file body reports the system error through put()).
bool isDiskFull(const beast::error_code& ec) {
  if (ec.category() != boost::system::system_category() && ec.category() != boost::system::generic_category())
    return false;
  return ec.value() == ENOSPC || ec.value() == EDQUOT || ec.value() == EFBIG;
}

// Bytes asked of one read. Unparsed bytes stay bounded: the header by header_limit, a chunk
// header line or the trailer section by maxHeaderBytes (see parse()).
constexpr std::size_t kReadSize = 64 * 1024;

bool isHttpError(const beast::error_code& ec) {
  return ec.category() == bhttp::make_error_code(bhttp::error::bad_target).category();
}

}  // namespace

HttpSession::HttpSession(tcp::socket&& socket, std::shared_ptr<ServerState> state)
    : stream_(std::move(socket)),
      executor_(stream_.get_executor()),
      state_(std::move(state)),
      rate_(state_->config.minBodyRate, state_->config.rateWindow),
      rateTimer_(executor_) {}

HttpSession::~HttpSession() {
  removeTempFile();
  unregister();
}

template <class... Args>
auto HttpSession::guarded(void (HttpSession::*fn)(Args...)) {
  return [self = shared_from_this(), fn](Args... args) {
    try {
      ((*self).*fn)(args...);
    } catch (const std::exception& e) {
      self->abort(e.what());
    } catch (...) {
      self->abort("unknown exception");
    }
  };
}

void HttpSession::abort(const char* what) noexcept {
  try {
    state_->log(std::string("http: ") + request_.method + " " + request_.path +
                ": connection closed after an exception: " + what);
  } catch (...) {
  }
  try {
    removeTempFile();
    closeNow();
  } catch (...) {
  }
}

void HttpSession::unregister() {
  if (id_) state_->remove(*id_);
  id_.reset();
}

void HttpSession::run() {
  beast::error_code ec;
  auto ep = stream_.socket().remote_endpoint(ec);
  if (!ec) remote_ = ep.address().to_string() + ":" + std::to_string(ep.port());
  id_ = state_->add(weak_from_this());
  if (!id_) {  // the server is stopping
    stream_.close();
    return;
  }
  // Start on the strand (the socket's executor) so every handler of this session is serialized.
  net::dispatch(executor_, guarded(&HttpSession::readHeader));
}

void HttpSession::close() {
  net::post(executor_, [self = shared_from_this()] {
    if (self->handedOff_) return;
    beast::error_code ec;
    self->stream_.socket().shutdown(tcp::socket::shutdown_both, ec);
    self->closeNow();
  });
}

void HttpSession::closeNow() {
  stopRateTimer();
  stream_.close();
}

void HttpSession::stopRateTimer() {
  watchingBody_ = false;
  if (rateTimerArmed_) rateTimer_.cancel();
}

void HttpSession::readHeader() {
  headerParser_.emplace();
  stringParser_.reset();
  fileParser_.reset();
  route_ = nullptr;
  request_ = Request{};
  keepAlive_ = false;
  head_ = false;
  version_ = 11;
  tooSlow_ = false;
  stage_ = Stage::Header;
  configureHeaderParser(*headerParser_, state_->config.maxHeaderBytes);
  // One deadline for the whole header however it trickles in: slowloris is cut here.
  stream_.expires_after(state_->config.readTimeout);
  parse();
}

void HttpSession::parse() {
  const std::size_t elementLimit = state_->config.maxHeaderBytes;
  beast::error_code ec;
  bool complete = false;
  bool elementTooLarge = false;
  try {
    // What bhttp::async_read does, inline, so that a parser exception (Beast throws
    // std::length_error for a field over 64 KiB, e.g. in a chunk trailer) is caught here.
    while (buffer_.size() > 0) {
      net::const_buffer data = buffer_.data();
      // A chunked body gets at most elementLimit bytes per put(): a chunk header line or the
      // trailer section that does not fit (Beast bounds neither) is then seen as such below.
      const bool chunked = stage_ == Stage::Body &&
                           (fileParser_ ? fileParser_->chunked() : stringParser_->chunked());
      if (chunked && data.size() > elementLimit) data = net::const_buffer(data.data(), elementLimit);
      std::size_t used = 0;
      if (fileParser_)
        used = fileParser_->put(data, ec);
      else if (stringParser_)
        used = stringParser_->put(data, ec);
      else
        used = headerParser_->put(data, ec);
      buffer_.consume(used);
      if (ec == bhttp::error::need_more) {
        ec = {};
        if (used > 0 && buffer_.size() > 0) continue;  // a new element starts: offer it the rest
        elementTooLarge = chunked && data.size() >= elementLimit;
        break;
      }
      if (ec) break;
      complete = stage_ == Stage::Header
                     ? headerParser_->is_header_done()
                     : (fileParser_ ? fileParser_->is_done() : stringParser_->is_done());
      if (complete || used == 0) break;
    }
  } catch (const std::exception& e) {
    state_->log(std::string("http: malformed request from ") + remote_ + ": " + e.what());
    removeTempFile();
    return sendError(400, "bad_request", "malformed request", stage_ == Stage::Header ? "headers" : "body",
                     true);
  }
  if (ec) return onParseError(ec);
  if (complete) return stage_ == Stage::Header ? onHeader() : onBody();
  if (elementTooLarge) {
    removeTempFile();
    return sendError(431, "chunk_header_too_large",
                     "a chunk header or the trailer section exceeds " + std::to_string(elementLimit) +
                         " bytes",
                     "body", true);
  }
  stream_.async_read_some(buffer_.prepare(kReadSize), guarded(&HttpSession::onRead));
}

void HttpSession::onRead(beast::error_code ec, std::size_t bytes) {
  if (ec) {
    if (tooSlow_ && ec == net::error::operation_aborted) {
      removeTempFile();
      const ServerConfig& cfg = state_->config;
      return sendError(408, "body_too_slow",
                       "the request body arrived slower than " +
                           std::to_string(cfg.minBodyRate / 1024) + " KiB/s over " +
                           std::to_string(cfg.rateWindow.count()) + " s",
                       "body", true);
    }
    // End of stream, the header deadline, a reset, or stop(): close quietly.
    removeTempFile();
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    closeNow();
    return;
  }
  buffer_.commit(bytes);
  if (stage_ == Stage::Body) rate_.add(bytes, std::chrono::steady_clock::now());
  parse();
}

void HttpSession::onParseError(beast::error_code ec) {
  started_ = std::chrono::steady_clock::now();
  if (request_.method.empty()) request_.method = "-";
  if (request_.path.empty()) request_.path = "-";
  removeTempFile();
  if (ec == bhttp::error::header_limit)
    return sendError(431, "header_too_large", "request header too large", "headers", true);
  if (ec == bhttp::error::body_limit)
    return sendError(413, "payload_too_large", "request body exceeds the limit", "body", true);
  if (stage_ == Stage::Body && isDiskFull(ec))
    return sendError(507, "insufficient_storage",
                     "the server's disk is full: cannot store the request body; free space or try again later",
                     "body", true);
  if (isHttpError(ec))
    return sendError(400, "bad_request",
                     (stage_ == Stage::Header ? "malformed request: " : "malformed request body: ") +
                         ec.message(),
                     stage_ == Stage::Header ? "headers" : "body", true);
  closeNow();
}

void HttpSession::onHeader() {
  started_ = std::chrono::steady_clock::now();
  const auto& h = headerParser_->get();
  request_.remote = remote_;
  keepAlive_ = h.keep_alive();
  version_ = h.version();
  head_ = h.method() == bhttp::verb::head;
  Routing routing = routeHead(*state_, h, request_);
  if (routing.answer) return send(std::move(*routing.answer), routing.close || !headerParser_->is_done());
  route_ = routing.route;
  if (route_->method == "WS") return upgrade();
  readBody();
}

void HttpSession::readBody() {
  const ServerConfig& cfg = state_->config;
  const bool stream = route_->options.streamBody;
  const std::uint64_t limit = stream ? cfg.maxUploadBytes : cfg.maxBodyBytes;
  const auto& h = headerParser_->get();
  if (auto refused = checkBodyLength(headerParser_->content_length(), limit))
    return sendError(refused->status, refused->code, refused->message, refused->field, true);
  const bool expectContinue =
      !headerParser_->is_done() && beast::iequals(h[bhttp::field::expect], "100-continue");

  if (stream) {
    tempFile_.adopt(state_->uploads.newPath());
    fileParser_.emplace(std::move(*headerParser_));
    headerParser_.reset();
    fileParser_->body_limit(limit);
    fileParser_->eager(true);
    beast::error_code ec;
    fileParser_->get().body().open(tempFile_.path().c_str(), beast::file_mode::write_new, ec);
    if (ec) {
      tempFile_.release();
      if (isDiskFull(ec))
        return sendError(507, "insufficient_storage",
                         "the server's disk is full: cannot store the request body; free space or try again later",
                         "body", true);
      return sendError(500, "internal", "cannot create upload file: " + ec.message(), "", true);
    }
  } else {
    stringParser_.emplace(std::move(*headerParser_));
    headerParser_.reset();
    stringParser_->body_limit(limit);
    stringParser_->eager(true);
  }
  stage_ = Stage::Body;
  if (expectContinue) {
    continue_ =
        std::make_shared<bhttp::response<bhttp::empty_body>>(bhttp::status::continue_, version_);
    stream_.expires_after(cfg.readTimeout);
    return bhttp::async_write(stream_, *continue_, guarded(&HttpSession::onContinueWritten));
  }
  startBodyRead();
}

void HttpSession::onContinueWritten(beast::error_code ec, std::size_t) {
  continue_.reset();
  if (ec) {
    removeTempFile();
    closeNow();
    return;
  }
  startBodyRead();
}

void HttpSession::startBodyRead() {
  const bool done = fileParser_ ? fileParser_->is_done() : stringParser_->is_done();
  if (done) return onBody();
  // The body is bounded by progress, not by one deadline: the rate timer watches it.
  stream_.expires_never();
  rate_.start(std::chrono::steady_clock::now());
  watchingBody_ = true;
  armRateTimer();
  parse();
}

void HttpSession::armRateTimer() {
  rateTimerArmed_ = true;
  rateTimer_.expires_at(rate_.deadline());
  rateTimer_.async_wait(guarded(&HttpSession::onRateTimer));
}

void HttpSession::onRateTimer(beast::error_code ec) {
  rateTimerArmed_ = false;
  // Cancelled, or already expired when the body completed or a response started.
  if (ec || !watchingBody_ || tooSlow_) return;
  if (std::chrono::steady_clock::now() < rate_.deadline()) return armRateTimer();  // progress
  // Too slow: cancel the read; onRead answers 408.
  tooSlow_ = true;
  beast::error_code ignored;
  stream_.socket().cancel(ignored);
}

void HttpSession::onBody() {
  stopRateTimer();
  if (fileParser_) {
    beast::error_code ignored;
    fileParser_->get().body().file().close(ignored);
    keepAlive_ = fileParser_->get().keep_alive();
    request_.bodyFile = tempFile_.path();
    std::error_code fec;
    const auto size = fs::file_size(tempFile_.path(), fec);
    request_.bodySize = fec ? 0 : static_cast<std::uint64_t>(size);
  } else {
    keepAlive_ = stringParser_->get().keep_alive();
    request_.body = stringParser_->release().body();
    request_.bodySize = request_.body.size();
  }
  if (route_->options.blocking) {
    if (auto quick = tryQuick(*route_, request_, *state_)) return respond(std::move(*quick));
    return runOnPool();
  }
  respond(invoke(*route_, request_, *state_));
}

void HttpSession::runOnPool() {
  // The session does nothing else while the job runs (no read is pending), so the job may read
  // request_ and route_; the response comes back through the strand.
  auto self = shared_from_this();
  // The pool takes turns between clients, a client being its address (without the port, so
  // opening more connections buys no more turns).
  const std::string client = remote_.substr(0, remote_.rfind(':'));
  const bool queued = state_->pool.trySubmit([self] {
    Response res = invoke(*self->route_, self->request_, *self->state_);
    auto done = [self, res = std::move(res)]() mutable {
      try {
        self->respond(std::move(res));
      } catch (const std::exception& e) {
        self->abort(e.what());
      } catch (...) {
        self->abort("unknown exception");
      }
    };
    net::post(self->executor_, std::move(done));
  }, client);
  if (queued) return;
  removeTempFile();
  Response r = Response::error(503, "busy",
                               "the server is busy with slow requests (imports, renders, PDMs); "
                               "retry shortly");
  r.headers.emplace_back("Retry-After", "2");
  send(std::move(r));
}

void HttpSession::respond(Response res) {
  removeTempFile();  // the handler moved it away if it keeps it
  send(std::move(res));
}

void HttpSession::upgrade() {
  if (!headerParser_->is_done())
    return sendError(400, "bad_request", "a WebSocket upgrade cannot carry a body", "body", true);
  std::shared_ptr<void> place;  // under the subscriber limits, before anything subscribes
  if (auto refused = admitSubscriber(*state_, request_.path, place)) return send(std::move(*refused));
  auto connection = std::make_shared<WsConnectionImpl>(state_);
  auto opened = openStream(*route_, request_, connection, *state_);
  if (auto* refused = std::get_if<Response>(&opened)) return send(std::move(*refused));
  std::shared_ptr<WsSource> source = std::get<std::shared_ptr<WsSource>>(std::move(opened));

  auto ws = std::make_shared<WebsocketSession>(std::move(stream_), state_, std::move(connection),
                                               std::move(source), request_.path, std::move(place));
  handedOff_ = true;
  unregister();
  ws->run(headerParser_->release());
}

void HttpSession::sendError(int status, const std::string& code, const std::string& message,
                            const std::string& field, bool close) {
  send(Response::error(status, code, message, field), close);
}

void HttpSession::send(Response res, bool close) {
  stopRateTimer();  // a response ends the body's reading, whether it was complete or not
  ResponseMessage out = responseMessage(std::move(res), {version_, keepAlive_ && !close, head_}, state_->config);
  std::visit([&](auto& msg) { write(std::move(msg), out.status, out.bytes, close); }, out.message);
}

template <class Message>
void HttpSession::write(std::shared_ptr<Message> msg, int status, std::uint64_t bytes, bool close) {
  logStatus_ = status;
  logBytes_ = bytes;
  closeAfterWrite_ = close || !msg->keep_alive();
  Message& ref = *msg;
  response_ = std::move(msg);
  // A stuck reader must not hold the connection forever; big files get time at 256 KiB/s.
  stream_.expires_after(std::max<std::chrono::steady_clock::duration>(state_->config.readTimeout,
                                                                      std::chrono::seconds(30)) +
                        std::chrono::seconds(bytes / (256 * 1024)));
  bhttp::async_write(stream_, ref, guarded(&HttpSession::onWrite));
}

void HttpSession::onWrite(beast::error_code ec, std::size_t) {
  response_.reset();
  if (state_->config.logRequests) {
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                        std::chrono::steady_clock::now() - started_)
                        .count();
    state_->log(request_.method + " " + request_.path + " " + std::to_string(logStatus_) + " " +
                std::to_string(logBytes_) + " " + std::to_string(ms) +
                (ec ? " (write failed)" : ""));
  }
  if (ec) {
    closeNow();
    return;
  }
  if (closeAfterWrite_) return lingeringClose();
  readHeader();
}

void HttpSession::lingeringClose() {
  beast::error_code ec;
  stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  if (ec) {
    closeNow();
    return;
  }
  stream_.expires_after(std::min<std::chrono::steady_clock::duration>(state_->config.readTimeout,
                                                                      std::chrono::seconds(5)));
  stream_.async_read_some(net::buffer(drain_), guarded(&HttpSession::onDrain));
}

void HttpSession::onDrain(beast::error_code ec, std::size_t) {
  if (ec) {  // EOF, the deadline, or stop()
    closeNow();
    return;
  }
  // Same deadline as before: the whole drain is bounded.
  stream_.async_read_some(net::buffer(drain_), guarded(&HttpSession::onDrain));
}

void HttpSession::removeTempFile() {
  if (tempFile_.empty()) return;
  if (fileParser_) {  // closed before it is removed
    beast::error_code ignored;
    fileParser_->get().body().file().close(ignored);
  }
  tempFile_.remove();
}

}  // namespace rover::http
