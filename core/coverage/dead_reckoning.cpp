#include "core/coverage/dead_reckoning.hpp"

#include <cmath>
#include <numbers>

namespace rover::coverage {

DeadReckoning::DeadReckoning(const LocalisationModel& model, std::uint64_t seed, int rover)
    : rng_(deriveSeed(deriveSeed(seed, 4), static_cast<std::uint64_t>(rover))),
      distanceStd_(model.distanceNoisePct / 100.0),
      headingStd_(model.headingNoiseDeg * std::numbers::pi / 180.0),
      slipPerDeg_(model.slipPctPerDeg / 100.0) {}

Eigen::Vector2d DeadReckoning::rotated(const Eigen::Vector2d& d) const {
  // cos(0) = 1 and sin(0) = 0 exactly: no heading error leaves d as it is.
  const double c = std::cos(headingError_), s = std::sin(headingError_);
  return {c * d.x() - s * d.y(), s * d.x() + c * d.y()};
}

Eigen::Vector2d DeadReckoning::closeLoop(double keep) {
  const Eigen::Vector2d before = error_;
  error_ *= keep;
  headingError_ *= keep;
  // true = believed + e stays put: the believed position moves by the error removed.
  return before - error_;
}

}  // namespace rover::coverage
