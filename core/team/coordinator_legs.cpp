// One leg of one rover: its pieces (waits, re-plans with new seeds, keep-out round a conflict)
// and what is recorded when it ends.
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

Coordinator::Outcome Coordinator::runPiece(int k, int i, int piece, const Eigen::Vector2d& goal, LegRecord& rec,
                 bool& reachedGoal) {
  const bool lastLeg = i + 1 == static_cast<int>(tasks_[k].legs.size());
  // The standing rovers' zones first (if the policy has them), then one per refused try.
  std::vector<KeepOutZone> keepOut = standingZones(k, here(k), goal);
  std::size_t standing = keepOut.size();
  std::optional<Candidate> firstTry;  // the first try within the attitude check
  std::optional<Conflict> conflict;
  std::optional<PathStatus> noPath;
  int zoneTries = 0;       // tries refused for a sample in a keep-out zone
  int unturnableEnds = 0;  // tries refused for ending where the rover cannot turn
  std::optional<Tilt> leastTilt;  // of the tries refused for tilting past the attitude check
  std::size_t zonesBefore = standing;  // keep-out zones of the previous try
  bool shortBefore = false;     // the previous try's plan ended short of a cut-off goal
  int unzonedRun = 0;           // policy_.unzonedConflictsEndReplans(): such tries in a row
  bool lastTry = false;         // policy_.repeatedShortEndsReplans(), unzonedConflictsEndReplans()
  for (int attempt = 0; attempt <= p_.maxReplans && !lastTry; ++attempt) {
    if (cancelled()) return Outcome::Cancelled;
    if (attempt > 0) {
      ++rec.replans;
      ++out_.replans;
    }
    // The last try added no keep-out zone (zones are only ever added).
    const bool sameZones = attempt > 0 && keepOut.size() == zonesBefore;
    zonesBefore = keepOut.size();
    // Then the next try is likely this problem again with the next seed, and a worker plans it
    // meanwhile (such runs of tries are much of a slow mission's RRT* time: .decisions/0002);
    // not when this try is likely the last (repeatedShortEndsReplans,
    // unzonedConflictsEndReplans). A try that does not count for the latter breaks its run.
    const int unzonedBefore = std::exchange(unzonedRun, 0);
    const int unzonedLimit = policy_.unzonedConflictsEndReplans();
    const bool likelyLast = (policy_.repeatedShortEndsReplans() && shortBefore && sameZones) ||
                            (unzonedLimit > 0 && unzonedBefore + 1 >= unzonedLimit);
    if (sameZones && !likelyLast && attempt < p_.maxReplans)
      ahead_->speculate(replan(k, i, piece, attempt + 1, goal, keepOut));
    PathResult path = tryPath(k, i, piece, attempt, goal, keepOut);
    if (path.status == PathStatus::Cancelled) return Outcome::Cancelled;
    const bool isShort = path.status == PathStatus::Approximate && path.goalCutOff;
    lastTry = policy_.repeatedShortEndsReplans() && isShort && shortBefore && sameZones;
    shortBefore = isShort;
    // The standing rovers' zones alone cut the goal off: a passage one of them stands in is
    // narrower than the zones (safety + 0.25 m each side) though not than the safety distance.
    // The piece plans on without them, as before them: its conflicts place the zones.
    if (standing > 0 && keepOut.size() == standing &&
        (isShort || path.status == PathStatus::NoSolution)) {
      keepOut.clear();
      standing = zonesBefore = 0;
      shortBefore = lastTry = false;
      if (attempt == p_.maxReplans) noPath = path.status;  // no re-plan left: the leg ends here
      continue;
    }
    if (!path.hasPath() || path.waypoints.size() < 2) {
      noPath = path.status;
      // Without a try's keep-out zones a new seed cannot turn an invalid start or goal valid.
      if (keepOut.size() == standing && path.status == PathStatus::InvalidGoal && policy_.invalidGoalEndsPiece()) {
        rec.note = "no path: invalid_goal (not on ground a rover may stop on)";
        return Outcome::InvalidGoal;
      }
      if (keepOut.size() == standing &&
          (path.status == PathStatus::InvalidGoal || path.status == PathStatus::InvalidStart))
        break;
      continue;
    }
    // Timed: a plan cut off from the goal by the keep-out zones of earlier tries, after a try
    // that reached the goal, is not driven: it would end the leg short of a goal the rover
    // reaches once the traffic has passed (the wait below). On the Kepler site with 20 rovers a
    // leg's 14th plan went 0.2 m, walled in by four tries' zones round a team mate passing by the
    // goal; the rover drove it, made no progress from there, and the leg ended 3 m short (issue 25).
    if (isShort && policy_.recovers() && firstTry && firstTry->reached) continue;
    const Candidate c0 = simulateTry(k, path.waypoints, 0, slipSeed(0x51ee5ull, k, i, piece, attempt));
    if (cancelled()) return Outcome::Cancelled;
    std::optional<Eigen::Vector2d> steep = firstExceedance(c0.samples);
    if (steep) {
      const Tilt t = steepestTilt(c0.samples);
      if (!leastTilt || t.angle < leastTilt->angle) leastTilt = t;
    }
    // Tilted while turning in place at the start: no path can help, only driving out straight.
    if (steep && policy_.recovers() && (*steep - here(k)).norm() < 0.1) {
      rec.note = tiltNote("turning where it stands, the rover", steepestTilt(c0.samples), "it");
      return Outcome::TiltsAtStart;
    }
    // Where the try ends the rover stops, and turns for its next move: ground it may turn on,
    // or the try is refused like a tilted one (a stop 0.2 m short of a valid vertex on 15°
    // ground left rovers unable to turn for the rest of the mission; ConflictPolicy::recovers).
    if (!steep && policy_.recovers() && !c0.samples.empty() && !planner_.canStop(xyOf(c0.samples.back()))) {
      steep = xyOf(c0.samples.back());
      ++unturnableEnds;
    }
    if (const auto zone = firstForbidden(c0.samples)) {
      // Into a keep-out zone: refused like a tilted try, whatever the policy.
      ++zoneTries;
      keepOutOf(k, goal, {*zone, 0.5}, keepOut);
      continue;
    }
    if (steep && !policy_.checksTiltedTries()) {
      keepOutOf(k, goal, {*steep, 0.5}, keepOut);
      continue;
    }
    // The leg's last piece decides whether the rover parks here for good.
    const bool parks = policy_.lastLegParks() && lastLeg && reachesGoal(c0, goal);
    std::optional<Conflict> first;
    for (int ticks : startDelays(k)) {
      conflict = firstConflict(k, c0.samples, ticks, parks ? kForGood : dwellTicks());
      if (!first) first = conflict;
      // Standing still already conflicts: so does every longer delay (it stands longer; the
      // delays ascend, coordinateWith checks).
      if (conflict && conflict->index < out_.trajectories[k].samples.size() + static_cast<std::size_t>(ticks))
        break;
      if (conflict || steep) continue;
      if (ticks > 0) {
        ++rec.waits;
        ++out_.waits;
        rec.waitTime += ticks * period_;
      }
      reachedGoal = path.status == PathStatus::Exact && c0.reached;
      commit(k, delayed(k, c0, ticks));
      return Outcome::Accepted;
    }
    conflict = first;
    // Waiting can only help a try that is within the attitude limit.
    if (!firstTry && !steep) firstTry = c0;
    // A conflict in the first second: no other path can dodge it, only waiting can.
    if (policy_.earlyConflictEndsReplans() && conflict && conflict->time - last(k).time < 1.0) break;
    // Keep out of where the other rover was, or of where the simulated rover tilted.
    const std::size_t zones = keepOut.size();
    keepOutOf(k, goal, conflict ? KeepOutZone{conflict->otherPosition, p_.keepOutRadius}
                                : KeepOutZone{*steep, 0.5},
              keepOut);
    // Only a try that reaches the goal and meets the other rover after its last driving sample
    // (started at once) counts: no path dodges that; one met on the way another path may.
    const std::size_t arrival = out_.trajectories[k].samples.size() + c0.samples.size();
    const bool unzoned = conflict && keepOut.size() == zones;
    if (unzoned && conflict->index >= arrival && reachesGoal(c0, goal)) unzonedRun = unzonedBefore + 1;
    if (unzonedLimit > 0 && unzonedRun >= unzonedLimit) lastTry = true;
  }
  if (!firstTry) {
    if (!noPath && zoneTries > 0) {
      rec.note = "every try enters a keep-out zone";
      return Outcome::KeepOut;
    }
    if (!noPath) {
      if (!leastTilt) rec.note = "every try ends where the rover cannot turn";
      else rec.note = tiltNote(unturnableEnds > 0 ? "every try ends where the rover cannot turn or" : "every try", *leastTilt);
      return Outcome::Steep;
    }
    rec.note = "no path: " + std::string(enumName(*noPath));
    return *noPath == PathStatus::InvalidGoal ? Outcome::InvalidGoal : Outcome::NoPath;
  }
  // Timed (recovers): before the leg is skipped, the first try within the limits started later
  // than the policy's delays, every wait_step up to one past the end of the traffic table (when
  // every rover planned so far has stopped for good). The policy's delays (max_waits ×
  // wait_step, 30 s by default) do not outlast a team mate's visit to a dead end: on the Kepler
  // site with 10 rovers, three rovers of one sub-team went in turn into a pocket of the crater
  // wall 3 m wide, and the third one's leg met the first or the second there at every delay up
  // to 30 s (issue 25). max_waits = 0 still means no waiting.
  if (policy_.recovers() && p_.maxWaits > 0) {
    const std::size_t now = out_.trajectories[k].samples.size();
    for (const int ticks : delaysUntilTrafficEnds(k, startDelays(k).back())) {
      if (cancelled()) return Outcome::Cancelled;
      const std::optional<Conflict> late = firstConflict(k, firstTry->samples, ticks, dwellTicks());
      // Standing still already conflicts: so does every longer wait.
      if (late && late->index < now + static_cast<std::size_t>(ticks)) break;
      if (late) continue;
      ++rec.waits;
      ++out_.waits;
      rec.waitTime += ticks * period_;
      reachedGoal = firstTry->reached && (firstTry->path.back() - goal).norm() < 1e-9;
      commit(k, delayed(k, *firstTry, ticks));
      return Outcome::Accepted;
    }
  }
  for (int w = 1; w <= policy_.waitsAfterReplans(); ++w) {
    if (cancelled()) return Outcome::Cancelled;
    const int ticks = static_cast<int>(std::lround(w * p_.waitStep / period_));
    Candidate c = simulateTry(k, firstTry->path, ticks, slipSeed(0x3a17ull, k, i, piece, w));
    const bool parks = policy_.lastLegParks() && lastLeg && reachesGoal(c, goal);
    conflict = firstConflict(k, c.samples, 0, parks ? kForGood : dwellTicks());
    if (!conflict && !firstExceedance(c.samples) && !firstForbidden(c.samples)) {
      rec.waits = w;
      out_.waits += w;
      reachedGoal = c.reached && (firstTry->path.back() - goal).norm() < 1e-9;
      commit(k, c);
      return Outcome::Accepted;
    }
  }
  rec.note = conflict ? conflictNote(*conflict) : "no clear try";
  boxedIn_ = conflict && conflict->time - last(k).time < 1.0;
  return Outcome::Skipped;
}

bool Coordinator::escapeTurn(int k, int i, int salt) {
  const Eigen::Vector2d from = here(k);
  const double heading = last(k).heading;
  int attempt = 0;
  for (int step = 0; step <= 18; ++step)
    for (int sign : {1, -1}) {
      if ((step == 0 || step == 18) && sign < 0) continue;
      const double psi = heading + sign * step * 10.0 * std::numbers::pi / 180.0;
      const Eigen::Vector2d dir(std::cos(psi), std::sin(psi));
      for (double d : {0.5, 1.0, 1.5}) {
        if (cancelled()) return false;
        const Eigen::Vector2d q = from + d * dir;
        if (!planner_.canStop(q)) continue;
        const Candidate c = simulateTry(k, {from, q}, 0, slipSeed(0xe5ca9eull, k, i, salt, attempt++));
        if (!c.reached || c.samples.empty() || firstExceedance(c.samples) || firstForbidden(c.samples) ||
            !planner_.canStop(xyOf(c.samples.back())))
          continue;
        for (int ticks : policy_.startDelays())
          if (!firstConflict(k, c.samples, ticks, dwellTicks())) {
            commit(k, delayed(k, c, ticks));
            return true;
          }
      }
    }
  return false;
}

bool Coordinator::blocksLaterGoal(int k, const Eigen::Vector2d& p) const {
  const double apart = p_.safetyDistance + 2 * p_.controller.acceptanceRadius;
  for (std::size_t j = 0; j < tasks_.size(); ++j) {
    if (rank_[j] <= rank_[static_cast<std::size_t>(k)]) continue;  // not planned after k
    for (const Leg& leg : tasks_[j].legs) {
      if ((leg.goal - p).norm() < apart) return true;
      for (const auto& v : leg.via)
        if ((v - p).norm() < apart) return true;
    }
  }
  return false;
}

void Coordinator::runLeg(int k, int i) {
  const Leg& leg = tasks_[k].legs[i];
  const Eigen::Vector2d goal = legGoal(leg);
  LegRecord rec;
  rec.rover = k;
  rec.leg = i;
  rec.target = leg.target;
  rec.startTime = last(k).time;
  rec.status = LegStatus::Short;
  // Recoveries (ConflictPolicy::recovers) are moves of their own, not pieces: the leg's
  // fixed points and pieces go on from where they left the rover.
  int recoveries = 0;
  for (int piece = 0; piece < p_.maxPieces;) {
    const double before = (here(k) - goal).norm();
    if (before <= p_.controller.acceptanceRadius) {
      rec.status = LegStatus::Reached;
      break;
    }
    bool reached = false;
    const Outcome o = runPiece(k, i, piece, goal, rec, reached);
    if (o == Outcome::Cancelled) {
      out_.cancelled = true;
      return;
    }
    // Or it is boxed in: every try, at every delay, came too close in its first second, while
    // standing is clear (issue 25: with 10 rovers on the default map a leg ended 1.06 m from
    // a rover not planned yet, which the traffic table holds standing at its start; the first
    // samples of any move, turning in place, came within 0.99 m of it, and the rover skipped
    // its 23 remaining legs from there). Driving off is the only way out.
    if (o == Outcome::Skipped && policy_.recovers() && recoveries < policy_.aside().recoveriesPerLeg &&
        (boxedIn_ || firstConflict(k, {}, 0, kForGood)) &&
        moveAside(k, policy_.aside().parkingMoves + recoveries)) {
      // Standing here it would be run over later: it stepped aside; the leg goes on from there.
      ++recoveries;
      rec.note.clear();
      continue;
    }
    if (o == Outcome::Skipped) {
      rec.status = LegStatus::Skipped;
      rec.reason = LegReason::Conflict;
      break;
    }
    if (o == Outcome::TiltsAtStart) {
      if (recoveries < policy_.aside().recoveriesPerLeg && escapeTurn(k, i, recoveries)) {
        ++recoveries;
        rec.note.clear();
        continue;
      }
      rec.reason = LegReason::Steep;
      break;
    }
    if (o == Outcome::InvalidGoal) {
      // A goal off passable ground is skipped outright, not "short" (when no piece moved the
      // rover yet).
      if (rec.pieces == 0) rec.status = LegStatus::Skipped;
      rec.reason = LegReason::InvalidGoal;
      break;
    }
    if (o == Outcome::NoPath || o == Outcome::Steep || o == Outcome::KeepOut) {  // Short
      rec.reason = o == Outcome::NoPath  ? LegReason::NoPath
                   : o == Outcome::Steep ? LegReason::Steep
                                         : LegReason::KeepOut;
      break;
    }
    ++rec.pieces;
    if (reached) {
      rec.status = LegStatus::Reached;
      break;
    }
    if ((here(k) - goal).norm() > before - 0.25) {  // no progress: stop chaining
      rec.note = "the tree ends " + oneDecimal((here(k) - goal).norm()) + " m short of the goal and makes no progress";
      rec.reason = LegReason::NoPath;
      break;
    }
    ++piece;
    if (piece == p_.maxPieces) {
      rec.note = "goal still " + oneDecimal((here(k) - goal).norm()) + " m away after max_pieces = " +
                 std::to_string(p_.maxPieces) + " RRT* pieces";
      rec.reason = LegReason::PiecesExhausted;
    }
  }
  if (rec.status == LegStatus::Reached) rec.reason = LegReason::None;
  rec.endTime = last(k).time;
  out_.legs.push_back(rec);
  ++legsDone_;
  if (observer_) observer_->legDone(rec, legsDone_, legsTotal_);
}

}  // namespace rover::team::detail
