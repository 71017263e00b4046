#pragma once
// The simulator stage (SPEC §3.3): drives a rover along a leg's waypoints and returns its 10 Hz
// samples. The coordinator only sees this interface, so a test can hand it a fake rover.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/team/rover_sim.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

class LegSimulator {
 public:
  virtual ~LegSimulator() = default;
  // Follows `waypoints` from `start` (at rest) with samples from `startTime` every sample period;
  // `slipSeed` seeds any random slip. Throws rover::Error for a start it cannot place (off the
  // map, next to nodata).
  virtual Trajectory drive(const std::vector<Eigen::Vector2d>& waypoints, const Pose& start,
                           double startTime, std::uint64_t slipSeed,
                           const CancelToken* cancel) const = 0;
};

// The skid-steered rover of rover_sim on the mission's DEM (holds a reference to it).
class RoverSimulator final : public LegSimulator {
 public:
  RoverSimulator(const terrain::Dem& dem, const RoverModel& model,
                 const ControllerParams& controller, const SlipParams& slip)
      : dem_(dem), model_(model), controller_(controller), slip_(slip) {}
  RoverSimulator(terrain::Dem&&, const RoverModel&, const ControllerParams&,
                 const SlipParams&) = delete;
  Trajectory drive(const std::vector<Eigen::Vector2d>& waypoints, const Pose& start,
                   double startTime, std::uint64_t slipSeed,
                   const CancelToken* cancel) const override {
    SlipParams slip = slip_;
    slip.seed = slipSeed;
    return simulate(dem_, waypoints, start, startTime, model_, controller_, slip, cancel);
  }

 private:
  const terrain::Dem& dem_;
  RoverModel model_;
  ControllerParams controller_;
  SlipParams slip_;
};

}  // namespace rover::team
