#include "server/api/elevation_compressor.hpp"

#include <algorithm>
#include <exception>
#include <iostream>
#include <sstream>

namespace rover::api {

ElevationCompressor::ElevationCompressor(Job job) : job_(std::move(job)), now_([] { return Clock::now(); }) {}

ElevationCompressor::~ElevationCompressor() { stop(); }

void ElevationCompressor::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    cancelRunning_ = true;
    queue_.clear();
    retryAt_.clear();
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

ElevationCompressor::Clock::duration ElevationCompressor::retryDelay(int failures) {
  Clock::duration d = kFirstRetryDelay;
  for (int i = 1; i < failures && d < kMaxRetryDelay; ++i) d *= 2;
  return std::min<Clock::duration>(d, kMaxRetryDelay);
}

void ElevationCompressor::enqueue(const std::string& mapId) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || running_ == mapId || retryAt_.count(mapId) ||
        std::find(queue_.begin(), queue_.end(), mapId) != queue_.end())
      return;
    failures_.erase(mapId);  // a map whose retries were used up starts afresh
    queue_.push_back(mapId);
    if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
  }
  changed_.notify_all();
}

void ElevationCompressor::cancel(const std::string& mapId) {
  std::unique_lock lock(mutex_);
  queue_.erase(std::remove(queue_.begin(), queue_.end(), mapId), queue_.end());
  retryAt_.erase(mapId);
  failures_.erase(mapId);
  if (running_ != mapId) return;
  cancelRunning_ = true;
  changed_.wait(lock, [&] { return running_ != mapId; });
}

bool ElevationCompressor::waitIdle(const std::string& mapId, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, timeout, [&] {
    return running_ != mapId && !retryAt_.count(mapId) &&
           std::find(queue_.begin(), queue_.end(), mapId) == queue_.end();
  });
}

ElevationCompressor::Status ElevationCompressor::status(const std::string& mapId) {
  std::lock_guard lock(mutex_);
  Status s;
  if (auto f = failures_.find(mapId); f != failures_.end()) s.failures = f->second;
  if (running_ == mapId) s.state = State::Running;
  else if (std::find(queue_.begin(), queue_.end(), mapId) != queue_.end()) s.state = State::Queued;
  else if (auto r = retryAt_.find(mapId); r != retryAt_.end()) {
    s.state = State::WaitingRetry;
    s.retryAt = r->second;
  } else if (s.failures > 0) s.state = State::GaveUp;
  return s;
}

void ElevationCompressor::setBeforeJob(Hook hook) {
  std::lock_guard lock(mutex_);
  beforeJob_ = std::move(hook);
}

void ElevationCompressor::setClock(std::function<Clock::time_point()> now) {
  {
    std::lock_guard lock(mutex_);
    now_ = std::move(now);
  }
  changed_.notify_all();
}

void ElevationCompressor::wake() {
  // Through the lock: a thread that read the clock before the test moved it is then waiting, and
  // is woken; one that reads it after sees it moved. (A notify between its read and its wait would
  // be lost, and it would sleep the old delay.)
  { std::lock_guard lock(mutex_); }
  changed_.notify_all();
}

void ElevationCompressor::queueDueRetriesLocked() {
  if (retryAt_.empty()) return;
  const auto now = now_();
  for (auto it = retryAt_.begin(); it != retryAt_.end();) {
    if (it->second <= now) {
      queue_.push_back(it->first);
      it = retryAt_.erase(it);
    } else {
      ++it;
    }
  }
}

void ElevationCompressor::run() {
  for (;;) {
    std::string id;
    Hook hook;
    {
      std::unique_lock lock(mutex_);
      for (;;) {
        if (stopping_) return;
        queueDueRetriesLocked();
        if (!queue_.empty()) break;
        if (retryAt_.empty()) {
          changed_.wait(lock);
        } else {
          // Asleep until the earliest retry is due (at most kMaxRetryDelay at a time: a test's
          // clock that does not move costs one wake-up per half hour), or until woken.
          Clock::time_point due = Clock::time_point::max();
          for (const auto& r : retryAt_) due = std::min(due, r.second);
          changed_.wait_for(lock, std::clamp<Clock::duration>(due - now_(), Clock::duration::zero(), kMaxRetryDelay));
        }
      }
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
    std::string failure;  // why the job failed ("" when it did not, or was cancelled)
    try {
      if (hook) hook(id, cancelled);
      if (!cancelled()) job_(id, cancelled);
    } catch (const std::exception& e) {
      if (!cancelled()) failure = e.what()[0] ? e.what() : "an error without a message";
    }
    {
      std::lock_guard lock(mutex_);
      running_.clear();
      if (failure.empty() || stopping_ || cancelRunning_) {
        failures_.erase(id);
      } else {
        // The map stays raw and readable. The line is written before the map's state changes,
        // so whoever sees the state sees the line logged.
        const int n = ++failures_[id];
        std::ostringstream line;
        line << "compressing map " << id << "'s elevation failed (attempt " << n << " of " << kAttempts
             << "; the map stays raw and readable): " << failure;
        if (n < kAttempts) {
          const auto delay = retryDelay(n);
          line << "; trying again in " << std::chrono::duration_cast<std::chrono::seconds>(delay).count() << " s";
          retryAt_[id] = now_() + delay;
        } else {
          line << "; not tried again before the server restarts";
        }
        std::cerr << line.str() << std::endl;
      }
    }
    changed_.notify_all();
  }
}

}  // namespace rover::api
