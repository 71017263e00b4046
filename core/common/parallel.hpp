#pragma once
// Runs fn(i) for i in [0, count) on `threads` threads (0 = all cores). Work is handed out one
// index at a time, so uneven runs balance; results must be written to per-index slots, which
// keeps a sweep's output independent of the thread count. The first exception is rethrown.
//
// A thread the system refuses to start (std::system_error: EAGAIN under a thread or memory limit;
// std::bad_alloc)
// is not an error: the threads already started and the calling thread share the work, so a busy
// server degrades to fewer cores instead of terminating (a joinable std::thread destroyed by the
// unwinding would call std::terminate).
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace rover {

inline unsigned hardwareThreads() {
  unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

// `spawn(worker)` starts one thread running `worker` (std::thread's constructor; tests pass one
// that refuses).
template <class Fn, class Spawn>
void parallelFor(std::size_t count, unsigned threads, Fn&& fn, Spawn&& spawn) {
  if (threads == 0) threads = hardwareThreads();
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex errorMutex;
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < count;) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(errorMutex);
        if (!error) error = std::current_exception();
        next.store(count);
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (unsigned t = 1; t < threads && t < count; ++t) {
    try {
      pool.push_back(spawn(worker));
    } catch (...) {
      break;  // fewer threads (EAGAIN, or no memory for one): those started and this one do every index
    }
  }
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

template <class Fn>
void parallelFor(std::size_t count, unsigned threads, Fn&& fn) {
  parallelFor(count, threads, std::forward<Fn>(fn), [](auto& worker) { return std::thread(worker); });
}

}  // namespace rover
