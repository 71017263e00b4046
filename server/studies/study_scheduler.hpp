#pragma once
// The order server studies run in (StudyManager): one at a time, first queued first, on a thread
// of its own. The executor decides how a study yields to the missions; this only queues.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace rover::studies {

class StudyScheduler {
 public:
  // `run` is called on the scheduler's thread for each study taken from the queue.
  explicit StudyScheduler(std::function<void(const std::string&)> run) : run_(std::move(run)) {}
  ~StudyScheduler() { stop(); }
  StudyScheduler(const StudyScheduler&) = delete;
  StudyScheduler& operator=(const StudyScheduler&) = delete;

  void start();  // once its owner is constructed (the queue may already hold studies)
  void push(const std::string& id);
  bool withdraw(const std::string& id);  // true when it was still waiting (and is no more)
  // No study starts from here on; `stopping()` is true before the owner cancels the running one.
  void beginStop();
  void stop();  // beginStop, then joins the thread
  bool stopping() const;

 private:
  void work();
  std::function<void(const std::string&)> run_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::string> queue_;
  bool stopping_ = false;
  std::thread worker_;
};

}  // namespace rover::studies
