#include "core/team/coordination.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "core/common/error.hpp"
#include "core/team/coordinator.hpp"

namespace rover::team {

void CoordinationParams::validate() const {
  rrt.validate();
  weights.validate();
  model.validate();
  controller.validate();
  slip.validate();
  if (!std::isfinite(safetyDistance) || safetyDistance < 0)
    throwInvalidParameter("safety_distance", "must be a finite number >= 0");
  if (maxReplans < 0 || maxReplans > 1000)
    throwInvalidParameter("max_replans", "must be an integer in [0, 1000]");
  if (!std::isfinite(waitStep) || !(waitStep > 0) || waitStep > 3600)
    throwInvalidParameter("wait_step", "must be a number of seconds in (0, 3600]");
  if (maxWaits < 0 || maxWaits > 1000)
    throwInvalidParameter("max_waits", "must be an integer in [0, 1000]");
  if (!std::isfinite(keepOutRadius) || keepOutRadius < 0)
    throwInvalidParameter("keep_out_radius", "must be a finite number >= 0");
  if (!std::isfinite(attitudeCheck) || attitudeCheck < 0 || attitudeCheck > std::numbers::pi / 2)
    throwInvalidParameter("attitude_check", "must be in [0, 90] degrees");
  if (!std::isfinite(dwellCheck) || dwellCheck < 0 || dwellCheck > 3600)
    throwInvalidParameter("dwell_check", "must be a number of seconds in [0, 3600]");
  if (maxPieces < 1 || maxPieces > 100)
    throwInvalidParameter("max_pieces", "must be an integer in [1, 100]");
  if (!std::isfinite(corridorRadius) || corridorRadius < 0.5 || corridorRadius > 100)
    throwInvalidParameter("corridor_radius", "must be a number of metres in [0.5, 100]");
  if (!std::isfinite(delayStep) || delayStep < controller.samplePeriod || delayStep > 3600)
    throwInvalidParameter("delay_step", "must be a number of seconds in [sample period, 3600]");
  // Timed: every try is checked at each delay, so their number bounds a mission's work (and the
  // delay list's memory): 61 with the defaults; max_waits 1000 × wait_step 3600 s / 0.1 s would
  // be 36 million per try.
  if (mode == CoordinationMode::Timed && maxWaits * waitStep / delayStep > kMaxStartDelays)
    throwInvalidParameter("delay_step", "max_waits × wait_step / delay_step (start delays per try) must be <= " +
                                            std::to_string(kMaxStartDelays));
}

TraversalLattice makeLattice(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                             const CoordinationParams& params) {
  return TraversalLattice(dem, classes, params.rrt.attitudeLimit, edgeResolutionOn(dem.geometry(), params.rrt),
                          params.weights, params.rrt.range, params.threads);
}

CoordinationParams resolveEvaluation(CoordinationParams params) {
  if (params.rrt.evaluation == EdgeEvaluation::Auto)
    params.rrt.evaluation = params.mode == CoordinationMode::Paper ? EdgeEvaluation::Sampled : EdgeEvaluation::Patch;
  return params;
}

namespace {

// coordinate() once the edge evaluation is resolved.
CoordinationResult coordinateResolved(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                      const std::vector<RoverTask>& tasks,
                                      const CoordinationParams& params, std::uint64_t seed,
                                      CoordinationObserver* observer, const CancelToken* cancel,
                                      const TraversalLattice* lattice) {
  const RoverSimulator simulator(dem, params.model, params.controller, params.slip);
  if (params.mode == CoordinationMode::Paper) {
    const BoxedRrtPlanner planner(dem, classes, params.rrt, params.weights);
    return coordinateWith(tasks, planner, simulator, PaperPolicy(params), params, seed, observer,
                          cancel);
  }
  std::optional<TraversalLattice> own;
  if (!lattice) lattice = &own.emplace(makeLattice(dem, classes, params));
  const GuidedRrtPlanner planner(dem, classes, *lattice, params.rrt, params.weights,
                                 params.corridorRadius);
  // The rovers leave in the departure order over the ground the lattice reaches from their
  // starts (the task builder ranks goals by the same order).
  std::vector<Eigen::Vector2d> starts;
  for (const RoverTask& t : tasks) starts.emplace_back(t.start.x, t.start.y);
  const Raster<std::uint8_t> ground = lattice->reachable(starts);
  const GroundDeparture departure = departureOverGround(starts, params.safetyDistance, ground);
  return coordinateWith(tasks, planner, simulator, TimedPolicy(params), params, seed, observer,
                        cancel, &departure.departure);
}

}  // namespace

CoordinationResult coordinate(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                              const std::vector<RoverTask>& tasks,
                              const CoordinationParams& params, std::uint64_t seed,
                              CoordinationObserver* observer, const CancelToken* cancel,
                              const TraversalLattice* lattice) {
  params.validate();
  return coordinateResolved(dem, classes, tasks, resolveEvaluation(params), seed, observer, cancel,
                            lattice);
}

}  // namespace rover::team
