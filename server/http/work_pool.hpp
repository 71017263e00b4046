#pragma once
// A fixed set of threads for slow request handlers (imports, renders, PDM discretisation, mission
// validation), so the io threads keep answering cheap requests (/api/health) while those run.
// Bounded: at most `maxQueued` jobs wait; beyond that trySubmit() refuses and the caller answers
// 503. A job must not throw (HttpSession wraps handlers in invokeHandler, which does not).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rover::http {

class WorkPool {
 public:
  WorkPool(unsigned threads, std::size_t maxQueued);
  ~WorkPool();  // stop()
  WorkPool(const WorkPool&) = delete;
  WorkPool& operator=(const WorkPool&) = delete;

  // Queues `job`; false when the queue is full or the pool is stopped (the job is not run).
  bool trySubmit(std::function<void()> job);
  // Lets the running jobs finish, drops the queued ones (destroying them on this thread) and
  // joins the threads. Idempotent.
  void stop();

  unsigned threads() const { return static_cast<unsigned>(threads_.size()); }
  std::size_t queued() const;  // waiting, not yet started
  std::size_t busy() const;    // running now

 private:
  void work();

  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> queue_;
  std::size_t maxQueued_;
  std::size_t busy_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> threads_;  // last: started once the rest is constructed
};

}  // namespace rover::http
