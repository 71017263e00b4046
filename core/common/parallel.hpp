#pragma once
// Runs fn(i) for i in [0, count) on `threads` threads (0 = all cores). Work is handed out one
// index at a time, so uneven runs balance; results must be written to per-index slots, which
// keeps a sweep's output independent of the thread count. The first exception is rethrown.
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace rover {

inline unsigned hardwareThreads() {
  unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

template <class Fn>
void parallelFor(std::size_t count, unsigned threads, Fn&& fn) {
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
  for (unsigned t = 1; t < threads && t < count; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace rover
