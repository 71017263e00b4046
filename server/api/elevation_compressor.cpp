#include "server/api/elevation_compressor.hpp"

#include <algorithm>
#include <exception>
#include <iostream>

namespace rover::api {

ElevationCompressor::ElevationCompressor(Job job) : job_(std::move(job)) {}

ElevationCompressor::~ElevationCompressor() { stop(); }

void ElevationCompressor::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    cancelRunning_ = true;
    queue_.clear();
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ElevationCompressor::enqueue(const std::string& mapId) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || running_ == mapId || std::find(queue_.begin(), queue_.end(), mapId) != queue_.end()) return;
    queue_.push_back(mapId);
    if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
  }
  changed_.notify_all();
}

void ElevationCompressor::cancel(const std::string& mapId) {
  std::unique_lock lock(mutex_);
  queue_.erase(std::remove(queue_.begin(), queue_.end(), mapId), queue_.end());
  if (running_ != mapId) return;
  cancelRunning_ = true;
  changed_.wait(lock, [&] { return running_ != mapId; });
}

bool ElevationCompressor::waitIdle(const std::string& mapId, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, timeout, [&] {
    return running_ != mapId && std::find(queue_.begin(), queue_.end(), mapId) == queue_.end();
  });
}

void ElevationCompressor::setBeforeJob(Hook hook) {
  std::lock_guard lock(mutex_);
  beforeJob_ = std::move(hook);
}

void ElevationCompressor::run() {
  for (;;) {
    std::string id;
    Hook hook;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
      running_ = id;
      cancelRunning_ = false;
      hook = beforeJob_;
    }
    const auto cancelled = [this] {
      std::lock_guard lock(mutex_);
      return cancelRunning_;
    };
    try {
      if (hook) hook(id, cancelled);
      if (!cancelled()) job_(id, cancelled);
    } catch (const std::exception& e) {
      // The map stays raw and readable; it is queued again at the next start.
      if (!cancelled()) std::cerr << "compressing map " << id << "'s elevation failed: " << e.what() << std::endl;
    }
    {
      std::lock_guard lock(mutex_);
      running_.clear();
    }
    changed_.notify_all();
  }
}

}  // namespace rover::api
