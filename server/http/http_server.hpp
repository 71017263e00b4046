#pragma once
// The Boost.Beast HTTP + WebSocket server (DESIGN.md: listener, http_session, websocket_session,
// one class per file). Owns the io_context and its threads; routes requests through a Router.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "server/http/router.hpp"

namespace rover::http {

struct ServerConfig {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;                   // 0 = an ephemeral port (tests)
  unsigned threads = 2;                         // io threads
  std::string webRoot;                          // static files for "/" ("" = none)
  std::string token;                            // non-empty: bearer auth on /api (except health)
  // More tokens, each with its operator's name (--token-file "name:token" lines; "" for a plain
  // line): any of them (or `token`) is accepted, and the request carries its name.
  std::vector<std::pair<std::string, std::string>> namedTokens;
  std::string corsOrigin;                       // non-empty: CORS for this origin
  // Host names answered besides the loopback names and `host` (request_origin.hpp); "*" = any.
  std::vector<std::string> publicNames;
  std::string uploadDir;                        // where streamed bodies are written
  std::uint64_t maxUploadBytes = 512ull << 20;  // streamed routes
  std::uint64_t maxBodyBytes = 4ull << 20;      // in-memory routes
  std::uint32_t maxHeaderBytes = 16 * 1024;    // request line + header fields; also a chunk
                                               // header line and the trailer section
  std::chrono::seconds readTimeout{30};        // the whole request header; an idle keep-alive
  // A body is cut (408) when it averages under minBodyRate bytes/s over any rateWindow: a steady
  // slow upload of any size passes, a stalled one does not. A body smaller than
  // minBodyRate·rateWindow must arrive within one window.
  std::uint64_t minBodyRate = 16 * 1024;
  std::chrono::seconds rateWindow{10};
  // The pool for RouteOptions::blocking handlers, and how many such requests may wait for it
  // (more are answered 503 with Retry-After).
  unsigned workThreads = 2;
  std::size_t workQueue = 32;
  bool logRequests = true;  // one line per request on stderr
  // WebSocket subscribers (issue 22): at most this many on one stream and on the whole server;
  // an upgrade beyond either is answered 503 with Retry-After.
  std::size_t maxStreamSubscribers = 64;
  std::size_t maxSubscribers = 1024;
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
