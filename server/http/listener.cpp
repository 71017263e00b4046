#include "server/http/listener.hpp"

#include <stdexcept>

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>

namespace rover::http {

Listener::Listener(net::io_context& ioc, std::shared_ptr<ServerState> state)
    : ioc_(ioc),
      strand_(net::make_strand(ioc)),
      acceptor_(strand_),
      backoff_(strand_),
      state_(std::move(state)) {}

void Listener::listen(const tcp::endpoint& endpoint) {
  beast::error_code ec;
  auto fail = [&](const char* what) {
    throw std::runtime_error("cannot listen on " + endpoint.address().to_string() + ":" +
                             std::to_string(endpoint.port()) + ": " + what + ": " + ec.message());
  };
  acceptor_.open(endpoint.protocol(), ec);
  if (ec) fail("open");
  acceptor_.set_option(net::socket_base::reuse_address(true), ec);
  if (ec) fail("set_option");
  acceptor_.bind(endpoint, ec);
  if (ec) fail("bind");
  acceptor_.listen(net::socket_base::max_listen_connections, ec);
  if (ec) fail("listen");
  port_ = acceptor_.local_endpoint(ec).port();
}

void Listener::run() {
  net::dispatch(strand_, beast::bind_front_handler(&Listener::accept, shared_from_this()));
}

void Listener::stop() {
  net::post(strand_, [self = shared_from_this()] {
    beast::error_code ec;
    self->acceptor_.close(ec);
    self->backoff_.cancel();
  });
}

void Listener::accept() {
  if (!acceptor_.is_open()) return;
  // Each connection gets its own strand: its handlers never run concurrently.
  acceptor_.async_accept(net::make_strand(ioc_),
                         beast::bind_front_handler(&Listener::onAccept, shared_from_this()));
}

void Listener::onAccept(beast::error_code ec, tcp::socket socket) {
  if (ec == net::error::operation_aborted || !acceptor_.is_open()) return;
  if (ec) {
    // E.g. out of file descriptors: log, wait a little, and keep accepting.
    if (state_->config.logRequests) state_->log("accept failed: " + ec.message());
    backoff_.expires_after(std::chrono::milliseconds(50));
    backoff_.async_wait([self = shared_from_this()](beast::error_code) { self->accept(); });
    return;
  }
  // A response goes out as soon as it is written (nginx's tcp_nodelay): with Nagle's algorithm a
  // response written in pieces (a header, then a file body's 4 KiB chunks) waits for the client's
  // delayed ACK, up to 40 ms on Linux, before its second piece leaves.
  beast::error_code nodelay;
  socket.set_option(tcp::no_delay(true), nodelay);  // best effort: a refusal only costs latency
  try {
    std::make_shared<HttpSession>(std::move(socket), state_)->run();
  } catch (const std::exception& e) {
    if (state_->config.logRequests) state_->log(std::string("session failed: ") + e.what());
  }
  accept();
}

}  // namespace rover::http
