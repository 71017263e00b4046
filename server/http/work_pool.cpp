#include "server/http/work_pool.hpp"

#include <algorithm>

namespace rover::http {

WorkPool::WorkPool(unsigned threads, std::size_t maxQueued)
    : maxQueued_(maxQueued), maxPerClient_(maxQueued < 4 ? maxQueued : maxQueued - maxQueued / 4) {
  const unsigned n = std::max(1u, threads);
  threads_.reserve(n);
  for (unsigned i = 0; i < n; ++i) threads_.emplace_back([this] { work(); });
}

WorkPool::~WorkPool() {
  stop();
}

bool WorkPool::trySubmit(std::function<void()> job, const std::string& client) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || queued_ >= maxQueued_) return false;
    auto& queue = queues_[client];
    if (queue.size() >= maxPerClient_) {
      if (queue.empty()) queues_.erase(client);
      return false;
    }
    if (queue.empty()) turns_.push_back(client);  // joins the round at its end
    queue.push_back(std::move(job));
    ++queued_;
  }
  ready_.notify_one();
  return true;
}

void WorkPool::stop() {
  std::unordered_map<std::string, std::deque<std::function<void()>>> dropped;
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
    dropped.swap(queues_);
    turns_.clear();
    queued_ = 0;
  }
  ready_.notify_all();
  for (auto& t : threads_)
    if (t.joinable()) t.join();
  threads_.clear();
  dropped.clear();  // outside the lock: a job's captures may take locks of their own
}

std::size_t WorkPool::queued() const {
  std::lock_guard lock(mutex_);
  return queued_;
}

std::size_t WorkPool::busy() const {
  std::lock_guard lock(mutex_);
  return busy_;
}

void WorkPool::work() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      ready_.wait(lock, [this] { return stopping_ || queued_ > 0; });
      if (stopping_) return;
      // The client whose turn it is gives one job, then goes to the end of the round if it has more.
      const std::string client = std::move(turns_.front());
      turns_.pop_front();
      auto it = queues_.find(client);
      job = std::move(it->second.front());
      it->second.pop_front();
      if (it->second.empty()) queues_.erase(it);
      else turns_.push_back(client);
      --queued_;
      ++busy_;
    }
    try {
      job();
    } catch (...) {
      // Jobs do not throw (see the header); nothing would be left to answer if one did.
    }
    job = nullptr;  // release its captures before counting it done
    std::lock_guard lock(mutex_);
    --busy_;
  }
}

}  // namespace rover::http
