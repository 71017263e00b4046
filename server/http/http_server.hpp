#pragma once
// The Boost.Beast HTTP + WebSocket server (DESIGN.md: listener, http_session, websocket_session,
// one class per file). Owns the io_context and its threads; routes requests through a Router.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "server/http/router.hpp"

namespace rover::http {

struct ServerConfig {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;                   // 0 = an ephemeral port (tests)
  unsigned threads = 2;                         // io threads
  std::string webRoot;                          // static files for "/" ("" = none)
  std::string token;                            // non-empty: bearer auth on /api (except health)
  std::string corsOrigin;                       // non-empty: CORS for this origin
  std::string uploadDir;                        // where streamed bodies are written
  std::uint64_t maxUploadBytes = 512ull << 20;  // streamed routes
  std::uint64_t maxBodyBytes = 4ull << 20;      // in-memory routes
  std::uint32_t maxHeaderBytes = 16 * 1024;
  std::chrono::seconds readTimeout{30};
  bool logRequests = true;  // one line per request on stderr
};

class HttpServer {
 public:
  HttpServer(ServerConfig config, const Router& router);
  ~HttpServer();
  // Binds and starts accepting on the io threads; throws std::runtime_error if it cannot bind.
  void start();
  unsigned short port() const;  // the bound port (after start)
  // Stops accepting, closes sessions, joins the threads. Idempotent.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rover::http
