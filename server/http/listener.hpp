#pragma once
// Accepts connections and starts an HttpSession for each, every socket on its own strand.
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include "server/http/http_session.hpp"

namespace rover::http {

class Listener : public std::enable_shared_from_this<Listener> {
 public:
  Listener(net::io_context& ioc, std::shared_ptr<ServerState> state);
  // Opens, binds and listens; throws std::runtime_error naming the endpoint when it cannot.
  void listen(const tcp::endpoint& endpoint);
  unsigned short port() const { return port_; }
  void run();   // starts accepting (call once, after listen)
  void stop();  // closes the acceptor on its strand; thread-safe

 private:
  void accept();
  void onAccept(beast::error_code ec, tcp::socket socket);

  net::io_context& ioc_;
  net::strand<net::io_context::executor_type> strand_;
  tcp::acceptor acceptor_;
  net::steady_timer backoff_;  // after an accept error (e.g. out of descriptors): no busy loop
  std::shared_ptr<ServerState> state_;
  unsigned short port_ = 0;
};

}  // namespace rover::http
