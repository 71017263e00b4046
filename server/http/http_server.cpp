#include "server/http/http_server.hpp"

#include <iostream>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "server/http/listener.hpp"

namespace rover::http {

struct HttpServer::Impl {
  Impl(ServerConfig c, const Router& router)
      : ioc(static_cast<int>(std::max(1u, c.threads))),
        pool(c.workThreads, c.workQueue),
        state(std::make_shared<ServerState>(std::move(c), router, pool)) {}

  net::io_context ioc;  // first member: destroyed last, after everything holding its objects
  WorkPool pool;        // stopped (joined) before the io_context goes
  std::shared_ptr<ServerState> state;
  std::shared_ptr<Listener> listener;
  std::vector<std::thread> threads;
  std::mutex mutex;
  bool started = false;
  bool stopped = false;
  unsigned short port = 0;
};

HttpServer::HttpServer(ServerConfig config, const Router& router)
    : impl_(std::make_unique<Impl>(std::move(config), router)) {}

HttpServer::~HttpServer() {
  stop();
}

void HttpServer::start() {
  std::lock_guard lock(impl_->mutex);
  if (impl_->started) throw std::runtime_error("HttpServer::start: already started");
  if (impl_->stopped) throw std::runtime_error("HttpServer::start: the server was stopped");
  const ServerConfig& cfg = impl_->state->config;

  tcp::endpoint endpoint;
  beast::error_code ec;
  const auto address = net::ip::make_address(cfg.host, ec);
  if (!ec) {
    endpoint = tcp::endpoint(address, cfg.port);
  } else {
    tcp::resolver resolver(impl_->ioc);
    auto results = resolver.resolve(cfg.host, std::to_string(cfg.port), ec);
    if (ec || results.empty())
      throw std::runtime_error("cannot listen on " + cfg.host + ":" + std::to_string(cfg.port) +
                               ": cannot resolve host: " + ec.message());
    endpoint = results.begin()->endpoint();
  }
  auto listener = std::make_shared<Listener>(impl_->ioc, impl_->state);
  listener->listen(endpoint);  // throws on failure (e.g. port in use)
  impl_->listener = listener;
  impl_->port = listener->port();
  listener->run();

  const unsigned n = std::max(1u, cfg.threads);
  impl_->threads.reserve(n);
  for (unsigned i = 0; i < n; ++i) {
    impl_->threads.emplace_back([impl = impl_.get()] {
      // Handlers never throw on purpose; if one does, log and keep the thread serving.
      for (;;) {
        try {
          impl->ioc.run();
          return;
        } catch (const std::exception& e) {
          impl->state->log(std::string("http: unhandled exception: ") + e.what());
        } catch (...) {
          impl->state->log("http: unhandled exception");
        }
      }
    });
  }
  impl_->started = true;
}

unsigned short HttpServer::port() const {
  return impl_->port;
}

void HttpServer::stop() {
  std::lock_guard lock(impl_->mutex);
  if (impl_->stopped) return;
  impl_->stopped = true;
  if (!impl_->started) {
    impl_->pool.stop();
    return;
  }

  impl_->state->beginStop();  // no new sessions; wake() becomes a no-op
  impl_->listener->stop();
  for (const auto& session : impl_->state->live()) session->close();
  // Give the sessions a moment to unwind on their strands (closing sockets aborts their
  // operations); whatever is left is destroyed with the io_context.
  impl_->state->waitUntilEmpty(std::chrono::seconds(2));
  impl_->ioc.stop();
  for (auto& t : impl_->threads)
    if (t.joinable()) t.join();
  impl_->threads.clear();
  // Running slow handlers finish (their responses are posted to the stopped io_context and
  // dropped with it); queued ones are dropped unrun.
  impl_->pool.stop();
  impl_->listener.reset();
}

}  // namespace rover::http
