#pragma once
// A fixed set of threads for slow request handlers (imports, renders, PDM discretisation, mission
// validation), so the io threads keep answering cheap requests (/api/health) while those run.
// Bounded: at most `maxQueued` jobs wait; beyond that trySubmit() refuses and the caller answers
// 503. A job must not throw (HttpSession runs handlers through invoke(), dispatch.hpp, which does not).
//
// Fair between clients (issue 22: 20 clients looping on one GET made another's upload wait 36 s):
// each client (the server passes the remote address) has its own FIFO queue and the threads serve
// the clients with work waiting in turn, one job each, so a client's next job waits behind at most
// one job of every other client, however many it has queued itself. One client may also hold at
// most three quarters of the waiting places (all of a queue of 1-3), so a looping client alone
// cannot make everyone else's requests answer 503.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace rover::http {

class WorkPool {
 public:
  WorkPool(unsigned threads, std::size_t maxQueued);
  ~WorkPool();  // stop()
  WorkPool(const WorkPool&) = delete;
  WorkPool& operator=(const WorkPool&) = delete;

  // Queues `job` for `client`; false when the queue (or the client's share of it) is full or the
  // pool is stopped (the job is not run).
  bool trySubmit(std::function<void()> job, const std::string& client = "");
  // Lets the running jobs finish, drops the queued ones (destroying them on this thread) and
  // joins the threads. Idempotent.
  void stop();

  unsigned threads() const { return static_cast<unsigned>(threads_.size()); }
  std::size_t queued() const;  // waiting, not yet started
  std::size_t busy() const;    // running now
  // The most jobs one client may have waiting.
  std::size_t maxQueuedPerClient() const { return maxPerClient_; }

 private:
  void work();

  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::unordered_map<std::string, std::deque<std::function<void()>>> queues_;  // per client, non-empty
  std::deque<std::string> turns_;  // clients with jobs waiting, in serving order (each once)
  std::size_t queued_ = 0;
  std::size_t maxQueued_, maxPerClient_;
  std::size_t busy_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> threads_;  // last: started once the rest is constructed
};

}  // namespace rover::http
