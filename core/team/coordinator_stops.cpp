// Where a rover may stop: parking after its last leg, stepping aside, and cutting a trajectory
// back to a stop that stays clear for the rest of the mission.
#include "core/team/coordinator_engine.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/common/error.hpp"
#include "core/common/parallel.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::team::detail {

void Coordinator::park(int k) {
  // Timed: where no spot stays clear for good the rover moves again before each next pass
  // (ours: higher-priority rovers may roam round a stopped one for long: .decisions/0002).
  // Paper: one move to a spot clear for good, as before.
  const int moves = policy_.aside().parkingMoves;
  for (int move = 0; move < moves; ++move) {
    if (!firstConflict(k, {}, 0, kForGood) && !blocksLaterGoal(k, here(k))) return;
    const std::optional<double> start = moveAside(k, move);
    if (!start) return;
    LegRecord rec;
    rec.rover = k;
    rec.leg = static_cast<int>(tasks_[k].legs.size());
    rec.startTime = *start;
    rec.endTime = last(k).time;
    rec.pieces = 1;
    rec.note = "parked out of the way";
    out_.legs.push_back(rec);
  }
}

void Coordinator::stopWhereSafe(int k) {
  const std::optional<Conflict> conflict = firstConflict(k, {}, 0, kForGood);
  if (!conflict) return;
  auto& samples = out_.trajectories[k].samples;
  std::vector<Stop>& stops = stops_[static_cast<std::size_t>(k)];
  std::size_t keep = stops.size() - 1;
  for (; keep > 0; --keep) {
    const std::size_t n = stops[keep].samples;
    if (n >= traffic_.end() || !traffic_.standing(k, xyOf(samples[n - 1]), n, traffic_.end())) break;
  }
  // Fewer legs are lost if the rover moves aside from a later stop to a spot clear for good:
  // the last kAsideStops stops after `keep`, latest first, one search each (a search that only
  // finds a spot clear for a while is undone).
  constexpr std::size_t kAsideStops = 3;
  const int legs = static_cast<int>(tasks_[k].legs.size());
  const std::vector<TrajectorySample> allSamples = samples;
  const std::vector<Eigen::Vector2d> allPath = out_.paths[k];
  const std::vector<Stop> allStops = stops;
  for (std::size_t j = allStops.size() - 1, tried = 0; j > keep && tried < kAsideStops && !cancelled(); --j, ++tried) {
    cutAt(k, j, *conflict);
    const std::optional<double> start = moveAside(k, policy_.aside().parkingMoves + policy_.aside().recoveriesPerLeg + 1 + static_cast<int>(tried));
    if (start && !firstConflict(k, {}, 0, kForGood)) {
      LegRecord rec;
      rec.rover = k;
      rec.leg = legs;
      rec.startTime = *start;
      rec.endTime = last(k).time;
      rec.pieces = 1;
      rec.note = "parked out of the way";
      // The undone legs' notes name where it left from, not where it stays.
      for (LegRecord& r : out_.legs)
        if (r.rover == k && r.note.starts_with("undone: "))
          r.note.replace(r.note.find("; it stops at "), 14, "; it moves aside from ");
      out_.legs.push_back(rec);
      return;
    }
    samples = allSamples;
    out_.paths[k] = allPath;
    stops = allStops;
    out_.legs = legsBefore_;
  }
  cutAt(k, keep, *conflict);
}

void Coordinator::cutAt(int k, std::size_t stop, const Conflict& conflict) {
  legsBefore_ = out_.legs;
  auto& samples = out_.trajectories[k].samples;
  std::vector<Stop>& stops = stops_[static_cast<std::size_t>(k)];
  samples.resize(stops[stop].samples);
  out_.paths[k].resize(stops[stop].path);
  stops.resize(stop + 1);
  const double cut = samples.back().time;
  const std::string note = "undone: standing at its end for the rest of the mission, the rover would be " +
                           conflictNote(conflict) + "; it stops at (" + oneDecimal(samples.back().x) +
                           ", " + oneDecimal(samples.back().y) + ") at t = " + oneDecimal(cut) + " s";
  const int legs = static_cast<int>(tasks_[k].legs.size());
  std::erase_if(out_.legs, [&](const LegRecord& r) { return r.rover == k && r.leg == legs && r.startTime >= cut; });
  for (LegRecord& r : out_.legs) {
    if (r.rover != k || r.endTime <= cut) continue;
    if (r.leg == legs) {  // a move aside under way at the cut (parking): it ends there
      r.endTime = cut;
      continue;
    }
    r.status = r.startTime < cut ? LegStatus::Short : LegStatus::Skipped;
    r.reason = LegReason::Conflict;
    r.startTime = std::min(r.startTime, cut);
    r.endTime = cut;
    r.note = note;
  }
}

std::optional<double> Coordinator::moveAside(int k, int move) {
  const AsideSearch& a = policy_.aside();
  const bool timed = a.readsTraffic;
  const Eigen::Vector2d from = here(k);
  std::vector<Eigen::Vector2d> spots;
  const auto& samples = out_.trajectories[k].samples;
  const double end = samples.back().distance;
  double next = 2.0;
  for (auto it = samples.rbegin(); it != samples.rend() && next <= a.backAlong; ++it) {
    if (end - it->distance < next) continue;
    spots.emplace_back(it->x, it->y);
    next += 2.0;
  }
  const int directions = a.directions;
  for (double radius : {1.5, 2.5, 3.5, 5.0, 7.0, 10.0, 14.0, 20.0, 28.0}) {
    if (radius > a.maxRing) break;
    for (int d = 0; d < directions; ++d) {
      const double a = d * 2 * std::numbers::pi / directions;
      spots.push_back(from + radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
  }
  struct Spot {
    Eigen::Vector2d at;
    bool forGood = true;
  };
  std::vector<Spot> ranked;
  const std::size_t now = out_.trajectories[k].samples.size();
  const long holdTicks = std::lround(a.minHold / period_);
  for (const Eigen::Vector2d& spot : spots) {
    if (!planner_.canStop(spot) || blocksLaterGoal(k, spot)) continue;
    if (!timed) {
      ranked.push_back({spot, true});
      continue;
    }
    // Standing there from the earliest arrival (the table clamps past the end: parked rovers).
    const double travel = (spot - from).norm() / p_.controller.nominalSpeed;
    const std::size_t arrive = now + static_cast<std::size_t>(travel / period_);
    const auto c = traffic_.standing(k, spot, arrive, std::max(arrive + 1, traffic_.end()));
    if (!c) ranked.push_back({spot, true});
    else if (static_cast<long>(c->index) - static_cast<long>(arrive) >= holdTicks) ranked.push_back({spot, false});
  }
  std::stable_partition(ranked.begin(), ranked.end(), [](const Spot& s) { return s.forGood; });
  int attempt = 0, rrtCalls = 0, simulations = 0;
  std::optional<Candidate> tilted;  // the first move that only exceeded the limit (second pass)
  for (const Spot& spot : ranked) {
    if (cancelled() || (timed && simulations == a.simulations)) break;
    const std::uint64_t planSeed = seedFor(seed_ ^ 0x9a4cull, k, attempt, move, 0);
    ++attempt;
    PathResult path;
    if (timed && planner_.edgeValid(from, spot.at)) {
      path.status = PathStatus::Exact;
      path.waypoints = {from, spot.at};
    } else {
      if (timed && rrtCalls == a.rrtCalls) continue;
      ++rrtCalls;
      ++out_.rrtCalls;
      path = planner_.plan(from, last(k).heading, spot.at, planSeed, {}, cancel_);
    }
    if (path.status != PathStatus::Exact || path.waypoints.size() < 2) continue;
    ++simulations;
    Candidate c = simulateTry(k, path.waypoints, 0, seedFor(seed_ ^ 0x9a4dull, k, attempt, move, 0));
    // A move that ends where it started (a spot back along a looping trajectory) is none.
    if (!c.reached || c.samples.empty() ||
        firstConflict(k, c.samples, 0, spot.forGood ? kForGood : holdTicks) || firstForbidden(c.samples))
      continue;
    if (firstExceedance(c.samples) || (timed && !planner_.canStop(xyOf(c.samples.back())))) {
      if (!tilted) tilted = std::move(c);
      continue;
    }
    const double start = c.samples.front().time;
    commit(k, c);
    return start;
  }
  if (!tilted) return std::nullopt;
  const double start = tilted->samples.front().time;
  commit(k, *tilted);
  return start;
}

}  // namespace rover::team::detail
