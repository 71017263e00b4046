#include "server/http/rate_floor.hpp"

#include <algorithm>

namespace rover::http {

RateFloor::RateFloor(std::uint64_t bytesPerSecond, Clock::duration window)
    : window_(std::max<Clock::duration>(window, std::chrono::milliseconds(100))),
      bucket_(window_ / 100) {
  const double seconds = std::chrono::duration<double>(window_).count();
  need_ = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(bytesPerSecond * seconds));
}

void RateFloor::start(Clock::time_point now) {
  total_ = 0;
  samples_.clear();
  samples_.push_back({now, 0});
}

void RateFloor::add(std::uint64_t bytes, Clock::time_point now) {
  total_ += bytes;
  // Merging credits the bytes up to one bucket early: the deadline errs strict by <= 1 %.
  if (!samples_.empty() && now - samples_.back().at < bucket_)
    samples_.back().total = total_;
  else
    samples_.push_back({now, total_});
  // The window ending at a sample's time + window starts at that sample: the body fails when
  // a window holds fewer than `need_` bytes, so the first sample with total + need > total_
  // ends it. Earlier samples never can again (total_ only grows): drop them.
  while (samples_.size() > 1 && samples_.front().total + need_ <= total_) samples_.pop_front();
}

RateFloor::Clock::time_point RateFloor::deadline() const {
  // After add(), the front sample is the first with total + need > total_ (the last one
  // always is).
  if (samples_.empty()) return Clock::time_point::max();
  return samples_.front().at + window_;
}

}  // namespace rover::http
