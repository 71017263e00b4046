#include "core/team/coordinator.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/common/error.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/rover_limits.hpp"
#include "core/team/coordinator_engine.hpp"

namespace rover::team {

PaperPolicy::PaperPolicy(const CoordinationParams& p) : waits_(p.maxWaits), dwell_(p.dwellCheck) {}

// The dwell: with 0.5 s a rover could arrive where it had no time to get away (7 skipped on the
// default map, seed 2); 4.5 s skipped fewer legs there (6 of 960 against 9) but left no time to
// step aside on real ground. The whole dwell_check (10 s by default): a stop checked for less
// left a rover no time to get out of the way when its next leg found no clear try
// (.decisions/0002).
// The standing rovers' zones: the safety distance plus half the departure margin (1.25 m by
// default), inside the way out the departure order guarantees each rover (safety + margin, less
// its grid step; planning/departure.hpp) and clear of every goal the task builder gives with
// sub-teams (safety + both acceptance circles + the margin from a later rover's start), with a
// quarter metre past the safety distance for the simulated rover's deviation from its path.
// Without them the planner met the standing rovers one conflict at a time, one zone per try: on
// the Kepler site with 40 rovers, 5 legs went round the formation's 3 × 3 m lattice of standing
// rovers by trial and error, each spending its 20 re-plans on 20 different standing rovers, and
// ended short or skipped (issue 25).
TimedPolicy::TimedPolicy(const CoordinationParams& p, StopRules rules)
    : rules_(rules),
      dwell_(p.dwellCheck),
      standing_(p.safetyDistance > 0 ? p.safetyDistance + planning::kDepartureMargin / 2 : 0.0) {
  const double period = p.controller.samplePeriod;
  const int step = std::max(1, static_cast<int>(std::lround(p.delayStep / period)));
  const int maxTicks = static_cast<int>(std::lround(p.maxWaits * p.waitStep / period));
  for (int ticks = 0; ticks <= maxTicks; ticks += step) delays_.push_back(ticks);
  // Higher-priority rovers may roam round a stopped one for long: it moves again before each
  // next pass, looks farther and reads the traffic table first (.decisions/0002).
  aside_.parkingMoves = 8;
  aside_.recoveriesPerLeg = 2;
  aside_.backAlong = 200.0;
  aside_.maxRing = 28.0;
  aside_.directions = 16;
  aside_.readsTraffic = true;
}


CoordinationResult coordinateWith(const std::vector<RoverTask>& tasks, const LegPlanner& planner,
                                  const LegSimulator& simulator, const ConflictPolicy& policy,
                                  const CoordinationParams& params, std::uint64_t seed,
                                  CoordinationObserver* observer, const CancelToken* cancel,
                                  const planning::Departure* departure) {
  params.validate();
  if (tasks.empty()) throw Error(ErrorCode::InvalidInput, "rovers", "rovers: none given");
  const std::vector<int>& delays = policy.startDelays();
  if (delays.empty() || delays.front() != 0 || policy.waitsAfterReplans() < 0 || !(policy.dwell() >= 0) ||
      std::adjacent_find(delays.begin(), delays.end(), [](int a, int b) { return b <= a; }) != delays.end())
    throw Error(ErrorCode::InvalidParameter, "coordination",
                "coordination: a policy starts each try without delay first, then at ascending delays");
  if (!policy.lastLegParks() && !policy.recovers())
    throw Error(ErrorCode::InvalidParameter, "coordination",
                "coordination: a policy that does not check last legs for good must recover (park "
                "steps aside before later passes)");
  planning::checkRoverCount(tasks.size());
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    const std::string field = "rovers[" + std::to_string(k) + "]";
    const Pose& s = tasks[k].start;
    if (!std::isfinite(s.x) || !std::isfinite(s.y) || !std::isfinite(s.heading))
      throw Error(ErrorCode::InvalidInput, field, field + ": start must be finite");
    for (const Leg& leg : tasks[k].legs) {
      bool finite = leg.goal.allFinite();
      for (const auto& v : leg.via) finite = finite && v.allFinite();
      if (!finite) throw Error(ErrorCode::InvalidInput, field, field + ": a leg goal is not finite");
    }
  }
  // Rovers boxed in by others leave after them (the table holds every rover at its start until
  // it is planned); one that cannot leave while the others stand is refused.
  planning::Departure open;
  if (!departure) {
    std::vector<Eigen::Vector2d> starts;
    for (const RoverTask& t : tasks) starts.emplace_back(t.start.x, t.start.y);
    open = planning::departureOrder(starts, params.safetyDistance);
    departure = &open;
  }
  std::vector<int> seen(tasks.size(), 0);
  bool once = departure->order.size() + departure->boxedIn.size() == tasks.size() &&
              departure->firstRound >= 0 && departure->firstRound <= static_cast<int>(departure->order.size());
  for (const auto* list : {&departure->order, &departure->boxedIn})
    for (int k : *list) once = once && k >= 0 && k < static_cast<int>(tasks.size()) && seen[static_cast<std::size_t>(k)]++ == 0;
  if (!once)
    throw Error(ErrorCode::InvalidParameter, "coordination",
                "coordination: the departure order must hold every rover once");
  if (!departure->boxedIn.empty()) {
    const std::string field = "rovers[" + std::to_string(departure->boxedIn.front()) + "]";
    throw Error(ErrorCode::InvalidInput, field,
                field + ": start is boxed in: no way out past the other rovers' starts keeping the safety distance "
                        "(+ " + detail::oneDecimal(planning::kDepartureMargin) + " m)");
  }
  return detail::Coordinator(tasks, departure->order, departure->firstRound, planner, simulator, policy, params, seed, observer,
                     cancel)
      .run();
}

}  // namespace rover::team
