// parallelFor (core/common/parallel.hpp): every index once, whatever the thread count, and a
// thread the system refuses to start is not an error.
#include <doctest/doctest.h>

#include <atomic>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <vector>

#include "core/common/parallel.hpp"

using rover::parallelFor;

TEST_CASE("parallelFor: every index exactly once on 1, 2 and 7 threads") {
  for (unsigned threads : {1u, 2u, 7u}) {
    std::vector<std::atomic<int>> seen(1000);
    parallelFor(seen.size(), threads, [&](std::size_t i) { seen[i].fetch_add(1); });
    int once = 0;
    for (auto& s : seen) once += s.load() == 1;
    CHECK(once == 1000);
  }
}

TEST_CASE("parallelFor: refused threads leave the work to those started and the caller") {
  // The system starts one thread, then refuses (EAGAIN, as under a thread limit): before, the
  // exception unwound past a joinable std::thread and terminated the process.
  for (int allowed : {0, 1, 2}) {
    CAPTURE(allowed);
    int started = 0;
    auto spawn = [&](auto& worker) {
      if (started == allowed) throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again));
      ++started;
      return std::thread(worker);
    };
    std::vector<std::atomic<int>> seen(500);
    parallelFor(seen.size(), 4, [&](std::size_t i) { seen[i].fetch_add(1); }, spawn);
    int once = 0;
    for (auto& s : seen) once += s.load() == 1;
    CHECK(once == 500);
    CHECK(started == allowed);
  }
}

TEST_CASE("parallelFor: the first exception is rethrown after every thread has joined") {
  auto spawn = [](auto& worker) { return std::thread(worker); };
  CHECK_THROWS_AS(parallelFor(100, 3, [](std::size_t i) { if (i == 17) throw std::runtime_error("index 17"); }, spawn),
                  std::runtime_error);
}
