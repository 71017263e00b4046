#pragma once
// A rover's speed and drive energy against mission time, for the page's charts synced to the
// replay (issue 13): one point a second of the 10 Hz trajectory, at the same times as the pitch
// and roll series.
#include <cstddef>
#include <vector>

#include "core/planning/plan_result.hpp"
#include "core/team/rover_sim.hpp"

namespace rover::team {

// Drive energy of the team rover by paper 000 eq. 5's forward term (coverage::forwardEnergy):
// m·g·(μ·cosθ + sinθ)·s / η between consecutive samples, with the team rover's mass and gravity.
// μ and η are paper 000's (0.15, 0.7): paper 001 gives no energy model. Turning on the spot is
// not counted (the skid-steered rover turns while it drives; eq. 5's spot turns do not happen).
struct DriveEnergy {
  double rollingResistance = 0.15;  // μ, paper 000
  double efficiency = 0.7;          // η, paper 000
};

// J from the first sample to the last, by the model above.
double driveEnergyJ(const Trajectory& t, const RoverModel& model, const DriveEnergy& e = {});

// Appends "speed_mps_rover_<rover>" (the mean surge speed of each second: a representative
// value, the 10 Hz speed is smooth) and "energy_j_rover_<rover>" (the energy used up to the
// second's first sample; its last point is the whole trajectory's), x = mission time (s).
// `every` = samples per second.
void motionSeries(const Trajectory& t, std::size_t every, int rover, const RoverModel& model,
                  std::vector<Series>& out, const DriveEnergy& e = {});

}  // namespace rover::team
