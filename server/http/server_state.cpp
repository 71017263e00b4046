#include "server/http/server_state.hpp"

#include <cstdio>

namespace rover::http {

ServerState::ServerState(ServerConfig c, const Router& r, WorkPool& p)
    : config(std::move(c)),
      origins(originPolicy(config.host, config.publicNames, config.corsOrigin)),
      router(r),
      statics(config.webRoot),
      pool(p),
      uploads(config.uploadDir) {}

std::optional<std::uint64_t> ServerState::add(std::weak_ptr<Closable> session) {
  std::lock_guard lock(mutex_);
  if (stopping_) return std::nullopt;
  const std::uint64_t id = nextId_++;
  sessions_.emplace(id, std::move(session));
  return id;
}

void ServerState::remove(std::uint64_t id) {
  std::lock_guard lock(mutex_);
  sessions_.erase(id);
  if (sessions_.empty()) emptied_.notify_all();
}

std::vector<std::shared_ptr<Closable>> ServerState::live() const {
  std::vector<std::shared_ptr<Closable>> out;
  std::lock_guard lock(mutex_);
  for (const auto& [id, weak] : sessions_)
    if (auto s = weak.lock()) out.push_back(std::move(s));
  return out;
}

bool ServerState::waitUntilEmpty(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return emptied_.wait_for(lock, timeout, [&] { return sessions_.empty(); });
}

void ServerState::beginStop() {
  {
    std::unique_lock gate(wakeGate_);
    stopped_ = true;
  }
  std::lock_guard lock(mutex_);
  stopping_ = true;
}

void ServerState::log(const std::string& line) const {
  static std::mutex logMutex;
  std::lock_guard lock(logMutex);
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace rover::http
