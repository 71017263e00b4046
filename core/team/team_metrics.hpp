#pragma once
// The metrics of a team mission (paper 001 §4, SPEC §3.5): trajectory lengths, mission time,
// attitude exceedances, separation, and the probability accumulated under the rovers' sensed
// discs against the distance they drove.
#include <cstddef>
#include <utility>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/team/coordination.hpp"
#include "core/team/route_search.hpp"

namespace rover::team {

// SPEC §3.5.
struct TeamMetrics {
  std::vector<double> trajectoryM;  // per rover, m over the ground
  double meanTrajectoryM = 0;
  double missionTimeS = 0;          // until the last rover stops
  std::size_t samples = 0;          // 10 Hz samples, all rovers
  std::size_t exceedances = 0;      // samples with |roll| or |pitch| > the attitude limit
  double exceedanceFraction = 0;
  double maxRollDeg = 0, maxPitchDeg = 0;
  int collisions = 0;               // episodes closer than the safety distance, any pair
  double minSeparationM = 0;
  double accumulatedProbability = 0;  // PDM mass inside the union of the sensed discs
  double singleRoverProbability = 0;  // the same for rover 0 alone
  double routeScore = 0;              // the route's own mass (search cells visited)
  int targets = 0;                    // route targets
  int targetsReached = 0;             // rover legs to a target slot that got there
  int targetsSkipped = 0;             // ... given up by wait-then-skip or off passable ground
  int targetsShort = 0;               // ... that ended away from the goal (no path)
  int targetsNoSlot = 0;              // (rover, target) pairs without valid ground for the slot
  int replans = 0, waits = 0, rrtCalls = 0;
};

// Accumulated probability vs distance (SPEC §3.5): PDM mass inside the union of the rovers'
// sensed discs (diameter `sensingDiameter`, map cells whose centre is inside), sampled every
// `every` samples. For the team, x is the mean distance per rover; `single` is rover 0 alone.
struct ProbabilityCurves {
  std::vector<std::pair<double, double>> team, single;
};
ProbabilityCurves accumulatedProbability(const Raster<float>& pdm,
                                         const std::vector<Trajectory>& trajectories,
                                         double sensingDiameter, std::size_t every = 50);

TeamMetrics teamMetrics(const CoordinationResult& plan, const ProbabilityCurves& curves,
                        const Route& route, double attitudeLimit, double safetyDistance);

}  // namespace rover::team
