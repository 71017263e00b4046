#pragma once
// Coverage under localisation error (issue 15). Paper 000 (Santra et al., §IV.D, §V, Table I)
// reached 95 % coverage in simulation but 80 % (clayey soil, MAE 0.41 m) and 65 % (sandy soil,
// MAE 0.32 m) in the field, "due to wheel slippage and localization errors", and found that loop
// closure in its graph SLAM "significantly contributed to achieving higher coverage". This is our
// grid stand-in for that, so a plan's fragility can be measured; the choices are ours.
//
// Each rover keeps two poses:
// - the believed pose, what the planner sees: a cell of its map (plus an offset from that cell's
//   centre, non-zero only after a loop closure moved the estimate) and one of the 8 headings;
// - the true pose = the believed position + an error vector e, and a heading error ψ.
//
// A move (dead reckoning): the planner picks the neighbour C of its believed cell as today and the
// rover drives to C's centre by odometry: the commanded displacement is d = centre(C) − believed
// position. What it truly drives is D = f·R(ψ)·d, where, drawn per move from the seeded generator:
//   ψ += N(0, heading_noise)                      the heading error is a random walk (the odometry
//                                                 integrates its heading as well)
//   f  = 1 + N(0, odometry_noise / 100) − slip    slip = min(0.9, slip_per_deg/100 · pitch°) on an
//                                                 uphill move, pitch from the true heights of the
//                                                 true start cell and the cell the move would end in
// The odometry reports d, so the believed position becomes centre(C) and e += D − d (kept as the
// difference, so zero noise stays exactly zero).
//
// A bump: a move whose true end lies in a true obstacle or off the field does not happen — the
// rover stays where it truly is, knows it did not move (a bumper, a stalled wheel), marks C an
// obstacle in its map and the bump is an incident. Only the end of a move is checked, as the
// planner allows diagonal moves between corner-touching obstacles.
// A rover whose map walls it in (bumps and smeared obstacles on all 8 sides) can never move again
// and stops (StopReason::NothingLeft) instead of waiting out the step budget.
//
// Sensing: the cells around the rover's *true* cell are read from the truth and written into its
// map around its *believed* cell (same offsets), so the map smears as the pose drifts; first
// writes stick as in the error-free planner.
//
// Loop closure (optional): when a move enters a cell of the map that was last entered at least
// loop_closure_gap moves (of the team) before, the rover has come back to a place it mapped: e and
// ψ shrink to loop_closure_keep of themselves, the believed position moving toward the truth (its
// believed cell may change; the map is not re-drawn, only the pose). A correction that would put
// the rover onto a team mate's cell or a cell its map holds as an obstacle, or off the map, waits
// for the next revisit.
//
// Metrics: the localisation error |e| after every move, its mean (paper 000 eq. 6 printed without
// its 1/N: MAE = (1/N)·Σ|x_est − x_true| over the N moves), max and last; true coverage (distinct
// cells the rover truly stood in) against the believed one; map accuracy (the share of mapped
// cells whose obstacle/free state is true); bumps; loop closures.
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>

#include "core/common/random.hpp"
#include "core/coverage/coverage_params.hpp"

namespace rover::coverage {

class DeadReckoning {
 public:
  DeadReckoning(const LocalisationModel& model, std::uint64_t seed, int rover);

  const Eigen::Vector2d& error() const { return error_; }  // true − believed position, m
  double headingError() const { return headingError_; }     // radians
  const Eigen::Vector2d& offset() const { return offset_; }  // believed position − cell centre

  // Draws this move's noise and returns the displacement truly driven for the commanded `d`.
  // `uphillDeg(D)` gives the pitch (deg, > 0 uphill) of a move of displacement D on the truth.
  template <class UphillDeg>
  Eigen::Vector2d drive(const Eigen::Vector2d& d, double commandedLength, UphillDeg uphillDeg) {
    headingError_ += headingStd_ * normalDraw(rng_);
    distanceFactor_ = 1.0 + distanceStd_ * normalDraw(rng_);
    Eigen::Vector2d D = rotated(d) * distanceFactor_;
    if (slipPerDeg_ > 0) {
      const double slip = std::min(0.9, slipPerDeg_ * std::max(0.0, uphillDeg(D)));
      distanceFactor_ -= slip;
      D = rotated(d) * distanceFactor_;
    }
    travelled_ = distanceFactor_ * commandedLength;
    return D;
  }
  // The horizontal distance of the last drive (f·|d|; |d| exactly as the caller gave it).
  double travelled() const { return travelled_; }
  // The drive happened: the odometry reports `d`, the believed position is the new cell's centre.
  void arrived(const Eigen::Vector2d& d, const Eigen::Vector2d& D) {
    error_ += D - d;
    offset_.setZero();
  }
  // Loop closure: the error shrinks to `keep` of itself; the believed position moves by the
  // difference. Returns the new believed position's shift (add it to the believed position).
  Eigen::Vector2d closeLoop(double keep);
  // After a loop closure moved the believed position into another cell: the offset from its centre.
  void setOffset(const Eigen::Vector2d& o) { offset_ = o; }
  // Undo a closeLoop whose jump was refused (team mate, obstacle, off the map).
  void undoLoop(const Eigen::Vector2d& error, double headingError) {
    error_ = error;
    headingError_ = headingError;
  }

 private:
  Eigen::Vector2d rotated(const Eigen::Vector2d& d) const;

  Rng rng_;
  double distanceStd_, headingStd_, slipPerDeg_;
  Eigen::Vector2d error_{0, 0}, offset_{0, 0};
  double headingError_ = 0, distanceFactor_ = 1, travelled_ = 0;
};

}  // namespace rover::coverage
