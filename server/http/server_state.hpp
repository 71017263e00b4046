#pragma once
// What every session of one server shares (Beast chat-multi's shared_state): the configuration,
// the route table, the static files, the work pool, the WebSocket admission counts, the names for
// streamed bodies, and the registry of live sessions that stop() closes. Sessions hold it by
// shared_ptr; it holds sessions only by weak_ptr, so a slow or dead client never pins memory.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "server/http/http_server.hpp"
#include "server/http/request_origin.hpp"
#include "server/http/router.hpp"
#include "server/http/static_files.hpp"
#include "server/http/temp_files.hpp"
#include "server/http/work_pool.hpp"
#include "server/http/ws_admission.hpp"

namespace rover::http {

// A live connection that stop() can close. close() is thread-safe (it posts to the strand).
class Closable {
 public:
  virtual ~Closable() = default;
  virtual void close() = 0;
};

class ServerState {
 public:
  ServerState(ServerConfig config, const Router& router, WorkPool& pool);

  const ServerConfig config;
  const OriginPolicy origins;  // from config: the Host allow-list and the CORS origin
  const Router& router;
  const StaticFiles statics;
  WorkPool& pool;  // owned by HttpServer, stopped after the io threads
  const std::shared_ptr<WsAdmission> websockets = std::make_shared<WsAdmission>();
  UploadFiles uploads;  // in config.uploadDir

  // Registry of live sessions. add() refuses (nullopt) once stopping.
  std::optional<std::uint64_t> add(std::weak_ptr<Closable> session);
  void remove(std::uint64_t id);
  std::vector<std::shared_ptr<Closable>> live() const;
  // Waits until every session has unregistered or `timeout` passed; true when none is left.
  bool waitUntilEmpty(std::chrono::milliseconds timeout);

  // Marks the server as stopping: no new sessions, and WsConnection::wake() becomes a no-op.
  void beginStop();
  // Held shared by wake() while it posts to a strand, so the io_context outlives the post.
  std::shared_mutex& wakeGate() { return wakeGate_; }
  bool stoppedLocked() const { return stopped_; }  // caller holds wakeGate()

  // One line on stderr (whole lines, never interleaved).
  void log(const std::string& line) const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable emptied_;
  std::unordered_map<std::uint64_t, std::weak_ptr<Closable>> sessions_;
  std::uint64_t nextId_ = 1;
  bool stopping_ = false;
  std::shared_mutex wakeGate_;
  bool stopped_ = false;  // guarded by wakeGate_
};

}  // namespace rover::http
