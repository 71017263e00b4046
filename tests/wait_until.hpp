#pragma once
// Waiting for events in tests (issue 23): a test waits for the condition it is about, never for
// a length of time, and asserts no duration. The deadline is not a figure under test: it only
// turns a hang into a failure that names what never happened, and is long enough that a loaded
// machine (two cores shared with builds) never reaches it.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace rover::test {

// The deadline for any wait in the tests: only a hang reaches it. Generous on purpose: the
// sanitizer build on a 2-core machine shared with another suite runs a default mission 10-20×
// slower than Release (a 30 s deadline failed there).
inline constexpr std::chrono::milliseconds kHangDeadline{std::chrono::seconds(600)};

// Polls `done` until it holds, backing off from 1 to 20 ms between polls (a poll may be an HTTP
// request); true if it came, false once `deadline` has passed. Safe on any thread.
template <class Predicate>
bool pollUntil(Predicate&& done, std::chrono::milliseconds deadline = kHangDeadline) {
  const auto until = std::chrono::steady_clock::now() + deadline;
  std::chrono::milliseconds pause{1};
  while (!done()) {
    if (std::chrono::steady_clock::now() >= until) return done();
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::milliseconds(20));
  }
  return true;
}

// Waits until `done` holds; FAILs the test case with `what` (what never happened) when
// `deadline` passes first. On the test case's thread only: FAIL ends the test case.
template <class Predicate>
void waitUntil(Predicate&& done, std::chrono::milliseconds deadline, const std::string& what) {
  if (!pollUntil(done, deadline)) FAIL("still waiting after " << deadline.count() << " ms for: " << what);
}

template <class Predicate>
void waitUntil(Predicate&& done, const std::string& what) {
  waitUntil(done, kHangDeadline, what);
}

// A gate a test opens once: threads it holds (a job, a handler, a fake) wait on a condition
// variable, not in a sleep loop, and are let go at once.
class Gate {
 public:
  void open() {
    {
      std::lock_guard lock(mutex_);
      open_ = true;
    }
    opened_.notify_all();
  }
  bool isOpen() const {
    std::lock_guard lock(mutex_);
    return open_;
  }
  // True once open; false when `deadline` passed first (the test failed elsewhere and never
  // opened it: the held thread then lets go rather than hang the suite).
  bool wait(std::chrono::milliseconds deadline = kHangDeadline) {
    std::unique_lock lock(mutex_);
    return opened_.wait_for(lock, deadline, [this] { return open_; });
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable opened_;
  bool open_ = false;
};

}  // namespace rover::test
