#include "server/studies/study_scheduler.hpp"

#include <algorithm>

namespace rover::studies {

void StudyScheduler::start() { worker_ = std::thread([this] { work(); }); }

void StudyScheduler::push(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(id);
  }
  cv_.notify_all();
}

bool StudyScheduler::withdraw(const std::string& id) {
  std::lock_guard lock(mutex_);
  const auto q = std::find(queue_.begin(), queue_.end(), id);
  if (q == queue_.end()) return false;
  queue_.erase(q);
  return true;
}

void StudyScheduler::beginStop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
}

void StudyScheduler::stop() {
  beginStop();
  if (worker_.joinable()) worker_.join();
}

bool StudyScheduler::stopping() const {
  std::lock_guard lock(mutex_);
  return stopping_;
}

void StudyScheduler::work() {
  for (;;) {
    std::string id;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
    }
    run_(id);
  }
}

}  // namespace rover::studies
