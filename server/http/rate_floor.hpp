#pragma once
// The deadline of a request body by progress: at least `bytesPerSecond` averaged over any
// `window` (so a body smaller than bytesPerSecond·window must arrive within one window). A
// steady slow upload is never cut, however long it takes; a stalled or trickling one is.
// Pure (no clock of its own) so it is testable; HttpSession feeds it every read.
#include <chrono>
#include <cstdint>
#include <deque>

namespace rover::http {

class RateFloor {
 public:
  using Clock = std::chrono::steady_clock;

  // bytesPerSecond 0 still needs one byte per window (an idle timeout of `window`).
  RateFloor(std::uint64_t bytesPerSecond, Clock::duration window);

  void start(Clock::time_point now);  // the body starts: nothing received yet
  void add(std::uint64_t bytes, Clock::time_point now);
  // When the body fails the floor if nothing more arrives: the window ending then would hold
  // fewer than bytesPerSecond·window bytes. Never moves backwards.
  Clock::time_point deadline() const;
  std::uint64_t received() const { return total_; }

 private:
  struct Sample {
    Clock::time_point at;
    std::uint64_t total;  // bytes received by `at`
  };
  std::uint64_t need_;     // bytes per window
  Clock::duration window_;
  Clock::duration bucket_;  // samples closer than this merge: at most ~100 kept per window
  std::uint64_t total_ = 0;
  std::deque<Sample> samples_;
};

}  // namespace rover::http
