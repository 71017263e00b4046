#include "core/team/coordinator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <memory>
#include <optional>
#include <utility>

#include "core/common/error.hpp"
#include "core/common/parallel.hpp"
#include "core/common/random.hpp"
#include "core/planning/departure.hpp"
#include "core/team/plan_ahead.hpp"
#include "core/team/separation.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::team {

PaperPolicy::PaperPolicy(const CoordinationParams& p) : waits_(p.maxWaits), dwell_(p.dwellCheck) {}

// The dwell: with 0.5 s a rover could arrive where it had no time to get away (7 skipped on the
// default map, seed 2); 4.5 s skipped fewer legs there (6 of 960 against 9) but left no time to
// step aside on real ground. The whole dwell_check (10 s by default): a stop checked for less
// left a rover no time to get out of the way when its next leg found no clear try
// (.decisions/0002).
TimedPolicy::TimedPolicy(const CoordinationParams& p, StopRules rules) : rules_(rules), dwell_(p.dwellCheck) {
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

namespace {

Eigen::Vector2d xyOf(const TrajectorySample& s) { return {s.x, s.y}; }

std::string oneDecimal(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

std::uint64_t seedFor(std::uint64_t seed, int rover, int leg, int piece, int attempt) {
  std::uint64_t s = deriveSeed(seed, static_cast<std::uint64_t>(rover));
  s = deriveSeed(s, static_cast<std::uint64_t>(leg));
  s = deriveSeed(s, static_cast<std::uint64_t>(piece));
  return deriveSeed(s, static_cast<std::uint64_t>(attempt));
}

Eigen::Vector2d legGoal(const Leg& leg) { return leg.via.empty() ? leg.goal : leg.via.back(); }

// Choices made here where the paper is silent are listed in coordination.hpp.
class Coordinator {
 public:
  Coordinator(const std::vector<RoverTask>& tasks, std::vector<int> order, int firstRound, const LegPlanner& planner,
              const LegSimulator& simulator, const ConflictPolicy& policy,
              const CoordinationParams& params, std::uint64_t seed,
              CoordinationObserver* observer, const CancelToken* cancel)
      : tasks_(tasks),
        order_(std::move(order)),
        firstRound_(firstRound),
        planner_(planner),
        simulator_(simulator),
        policy_(policy),
        p_(params),
        seed_(seed),
        observer_(observer),
        cancel_(cancel),
        period_(params.controller.samplePeriod),
        traffic_(params.safetyDistance, params.controller.samplePeriod) {}

  CoordinationResult run() {
    const int n = static_cast<int>(tasks_.size());
    out_.trajectories.resize(n);
    out_.paths.resize(n);
    rank_.assign(static_cast<std::size_t>(n), 0);
    for (int r = 0; r < n; ++r) rank_[static_cast<std::size_t>(order_[static_cast<std::size_t>(r)])] = r;
    // Every rover stands at its start from t = 0 until it is planned (issue 25): a rover planned
    // earlier never comes closer than the safety distance to one still standing there.
    for (int k = 0; k < n; ++k) {
      startRover(k);
      traffic_.add(out_.trajectories[k]);
    }
    for (const auto& t : tasks_) legsTotal_ += static_cast<int>(t.legs.size());
    planAhead();
    for (int k : order_) {
      if (out_.cancelled) break;
      for (int i = 0; i < static_cast<int>(tasks_[k].legs.size()); ++i) {
        runLeg(k, i);
        if (out_.cancelled) break;
      }
      if (!out_.cancelled) {
        park(k);
        stopWhereSafe(k);
      }
      traffic_.replace(k, out_.trajectories[k]);  // rover k is done: the next ones plan round it
    }
    // Rover-major whatever the order the rovers left in.
    std::stable_sort(out_.legs.begin(), out_.legs.end(),
                     [](const LegRecord& a, const LegRecord& b) { return a.rover < b.rover; });
    out_.rrtCalls += ahead_->finish();  // every leg's plan, used or not: as many whatever the threads
    // Every pair of rovers over every sample: skipped once cancelled (the plan is unfinished
    // anyway, and for 64 rovers far into a long route it is seconds the cancel would wait for).
    if (!cancelled()) out_.conflicts = checkSeparation(out_.trajectories, p_.safetyDistance).conflicts;
    return std::move(out_);
  }

 private:
  enum class Outcome { Accepted, Skipped, NoPath, InvalidGoal, Steep, TiltsAtStart, KeepOut, Cancelled };

  struct Candidate {
    std::vector<Eigen::Vector2d> path;         // waypoints, the rover's position first
    std::vector<TrajectorySample> samples;     // new samples (waits, then driving)
    bool reached = false;                      // the simulation entered the last waypoint's circle
  };


  bool cancelled() const { return cancel_ && cancel_->cancelled(); }
  const TrajectorySample& last(int k) const { return out_.trajectories[k].samples.back(); }
  Eigen::Vector2d here(int k) const { return xyOf(last(k)); }
  std::uint64_t slipSeed(std::uint64_t salt, int k, int i, int piece, int attempt) const {
    return seedFor(deriveSeed(seed_ ^ salt, p_.slip.seed), k, i, piece, attempt);
  }

  // The first sample: the rover at rest on its start (a drive with the start as its only
  // waypoint records exactly that, with the terrain height and attitude).
  void startRover(int k) {
    const Pose& s = tasks_[k].start;
    Trajectory t;
    try {
      t = simulator_.drive({Eigen::Vector2d(s.x, s.y)}, s, 0.0, p_.slip.seed, nullptr);
    } catch (const Error&) {
      const std::string field = "rovers[" + std::to_string(k) + "]";
      throw Error(ErrorCode::InvalidInput, field,
                  field + ": start is outside the map or next to nodata");
    }
    t.samples.resize(1);
    t.samples[0].time = 0;
    t.status = SimStatus::Reached;
    out_.trajectories[k] = std::move(t);
    out_.paths[k].push_back({s.x, s.y});
    stops_.push_back({{1, 1}});
  }

  // Every planned leg from its nominal start, planned ahead on the threads the caller granted
  // while the rovers are coordinated (plan_ahead.hpp). A via leg (hybrid) whose fixed points a
  // rover may drive is not planned; one that it may not is planned ahead too.
  void planAhead() {
    std::vector<PlanAhead::Job> jobs;
    for (int k = 0; k < static_cast<int>(tasks_.size()); ++k) {
      const RoverTask& task = tasks_[k];
      firstJob_.push_back(jobs.size());
      Eigen::Vector2d start(task.start.x, task.start.y);
      double heading = task.start.heading;
      for (int i = 0; i < static_cast<int>(task.legs.size()); ++i) {
        const Leg& leg = task.legs[i];
        const Eigen::Vector2d goal = legGoal(leg);
        jobs.push_back({start, heading, goal, seedFor(seed_, k, i, 0, 0), leg.via.empty() || !viaValid(start, leg)});
        if ((goal - start).norm() > 1e-9) heading = std::atan2(goal.y() - start.y(), goal.x() - start.x());
        start = goal;
      }
    }
    const unsigned threads = p_.threads == 0 ? hardwareThreads() : p_.threads;
    ahead_ = std::make_unique<PlanAhead>(planner_, std::move(jobs), threads > 1 ? threads - 1 : 0, cancel_);
  }

  // Every straight move of a via leg's fixed points, from `from`, is one the rover may drive.
  bool viaValid(const Eigen::Vector2d& from, const Leg& leg) const {
    Eigen::Vector2d a = from;
    for (const auto& v : leg.via) {
      if (!planner_.edgeValid(a, v)) return false;
      a = v;
    }
    return true;
  }

  // The path of one try: the fixed points of a via leg (first try, if every edge is valid), the
  // path planned ahead (first try, if the rover stopped where that plan started), else a plan now.
  PathResult tryPath(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                     const std::vector<KeepOutZone>& keepOut) {
    const Leg& leg = tasks_[k].legs[i];
    const Eigen::Vector2d from = here(k);
    if (attempt == 0 && piece == 0 && !leg.via.empty() && viaValid(from, leg)) {
      PathResult r;
      r.waypoints.push_back(from);
      r.waypoints.insert(r.waypoints.end(), leg.via.begin(), leg.via.end());
      r.status = PathStatus::Exact;
      return r;
    }
    if (attempt == 0 && piece == 0) {
      const std::size_t j = firstJob_[static_cast<std::size_t>(k)] + static_cast<std::size_t>(i);
      const PlanAhead::Job& a = ahead_->job(j);
      if (a.planned && (a.start - from).norm() <= p_.controller.acceptanceRadius + 0.05) {
        const PathResult* ahead = ahead_->get(j);
        if (ahead->hasPath()) {
          PathResult r = *ahead;
          r.waypoints.front() = from;
          return r;
        }
      }
    }
    ++out_.rrtCalls;
    return ahead_->plan(replan(k, i, piece, attempt, goal, keepOut));
  }

  PlanAhead::Request replan(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                            const std::vector<KeepOutZone>& keepOut) const {
    return {here(k), last(k).heading, goal, seedFor(seed_, k, i, piece, attempt), keepOut};
  }

  // Rover k standing where it is for `ticks` samples, appended to `samples`.
  void stand(int k, int ticks, std::vector<TrajectorySample>& samples) const {
    const TrajectorySample origin = last(k);
    const std::size_t base = out_.trajectories[k].samples.size() - 1;  // index of `origin`
    for (int j = 1; j <= ticks; ++j) {
      TrajectorySample s = origin;
      s.time = static_cast<double>(base + j) * period_;
      s.speed = 0;
      samples.push_back(s);
    }
  }

  // The rover stands `waitTicks` samples, then drives `path`.
  Candidate simulateTry(int k, const std::vector<Eigen::Vector2d>& path, int waitTicks,
                        std::uint64_t seed) {
    const TrajectorySample origin = last(k);
    const std::size_t base = out_.trajectories[k].samples.size() - 1;  // index of `origin`
    Candidate c;
    c.path = path;
    stand(k, waitTicks, c.samples);
    std::vector<Eigen::Vector2d> waypoints(path.begin() + 1, path.end());
    if (waypoints.empty()) {
      c.reached = true;
      return c;
    }
    const std::size_t startIndex = base + waitTicks;
    Trajectory sim = simulator_.drive(waypoints, {origin.x, origin.y, origin.heading},
                                      static_cast<double>(startIndex) * period_, seed, cancel_);
    for (std::size_t m = 1; m < sim.samples.size(); ++m) {
      TrajectorySample s = sim.samples[m];
      s.time = static_cast<double>(startIndex + m) * period_;
      s.distance += origin.distance;
      c.samples.push_back(s);
    }
    c.reached = sim.status == SimStatus::Reached;
    return c;
  }

  // `c` started `ticks` samples later: the rover stands where it is meanwhile. The terrain does
  // not change, so the simulated motion is the same, only later.
  Candidate delayed(int k, const Candidate& c, int ticks) const {
    if (ticks == 0) return c;
    Candidate d;
    d.path = c.path;
    d.reached = c.reached;
    d.samples.reserve(c.samples.size() + static_cast<std::size_t>(ticks));
    stand(k, ticks, d.samples);
    for (TrajectorySample s : c.samples) {
      s.time += ticks * period_;
      d.samples.push_back(s);
    }
    return d;
  }

  // `stand` for firstConflict: standing for as long as any higher-priority rover moves.
  static constexpr long kForGood = -1;
  long dwellTicks() const { return std::lround(policy_.dwell() / period_); }

  // The first conflict with a higher-priority rover (the traffic table holds exactly those) of
  // rover k standing where it is for `ticks` samples, then driving `samples` (appended to its
  // trajectory after them); then standing at its last position for `stand` samples, or, with
  // kForGood, for as long as any higher-priority rover moves.
  std::optional<Conflict> firstConflict(int k, std::span<const TrajectorySample> samples, int ticks,
                                        long stand) const {
    const bool parkedForGood = stand == kForGood;
    const std::size_t base = out_.trajectories[k].samples.size();
    if (ticks > 0)
      if (auto c = traffic_.standing(k, here(k), base, base + static_cast<std::size_t>(ticks)))
        return c;
    const std::size_t from = base + static_cast<std::size_t>(ticks);
    if (auto c = traffic_.driving(k, samples, from)) return c;
    std::size_t end = traffic_.end();
    const std::size_t after = from + samples.size();
    if (!parkedForGood) end = std::min(end, after + static_cast<std::size_t>(std::max(0L, stand)));
    if (after >= end) return std::nullopt;
    const Eigen::Vector2d p = samples.empty() ? here(k) : xyOf(samples.back());
    return traffic_.standing(k, p, after, end);
  }

  // The delays at which runPiece starts a try: the policy's; for a rover the departure order
  // holds back (not in its first round: its way out opens only once rovers round it have left)
  // that has not left its start yet, when the policy recovers (timed), more, every wait_step up
  // to one past the end of the traffic table, when every rover planned so far stands where it
  // stays. Such a rover may stand at its start as long as it likes: every rover planned before it
  // kept the safety distance from it standing there for the whole mission. So a rover inside a
  // formation waits until the rovers that left before it have driven off (issue 25: with 64
  // rovers the last of a 2 × 2 block met team mates driving out past it at every delay up to
  // max_waits × wait_step and skipped all its 5 legs without moving). Rovers free to leave at
  // once keep the policy's delays.
  std::vector<int> startDelays(int k) const {
    std::vector<int> delays = policy_.startDelays();
    if (!policy_.recovers() || rank_[static_cast<std::size_t>(k)] < firstRound_ ||
        stops_[static_cast<std::size_t>(k)].size() > 1)
      return delays;
    const int step = std::max(1, static_cast<int>(std::lround(p_.waitStep / period_)));
    const std::size_t now = out_.trajectories[k].samples.size();
    for (std::size_t t = static_cast<std::size_t>(delays.back()) + step; now + t < traffic_.end() + step; t += step)
      delays.push_back(static_cast<int>(t));
    return delays;
  }

  // The steepest |roll| or |pitch| of a try (rad) and which of the two it was: what a leg's note
  // reports beside the attitude check it was refused against (issue 27: a note that named "the
  // attitude limit" while the operator's attitude_limit was 45° and the try tilted 15.0°).
  struct Tilt {
    double angle = 0;
    bool pitch = false;
  };
  static Tilt steepestTilt(const std::vector<TrajectorySample>& samples) {
    Tilt t;
    for (const auto& s : samples) {
      if (std::abs(s.roll) > t.angle) t = {std::abs(s.roll), false};
      if (std::abs(s.pitch) > t.angle) t = {std::abs(s.pitch), true};
    }
    return t;
  }
  std::string tiltNote(const char* what, const Tilt& reached, const char* reachedBy = "the least tilted try") const {
    constexpr double kDeg = 180.0 / std::numbers::pi;
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s tilts past attitude_check %.1f° (%s reached %.1f° %s)",
                  what, p_.attitudeCheck * kDeg, reachedBy, reached.angle * kDeg, reached.pitch ? "pitch" : "roll");
    return buf;
  }

  // The first sample with |roll| or |pitch| above the attitude check, if any.
  std::optional<Eigen::Vector2d> firstExceedance(const std::vector<TrajectorySample>& samples) const {
    if (!(p_.attitudeCheck > 0)) return std::nullopt;
    for (const auto& s : samples)
      if (std::abs(s.roll) > p_.attitudeCheck || std::abs(s.pitch) > p_.attitudeCheck)
        return xyOf(s);
    return std::nullopt;
  }

  // The first sample on a keep-out zone's cell, if any: such a try is never committed (the
  // planned path keeps out, but the simulated rover cuts corners and slips).
  std::optional<Eigen::Vector2d> firstForbidden(const std::vector<TrajectorySample>& samples) const {
    for (const auto& s : samples)
      if (planner_.forbidden(xyOf(s))) return xyOf(s);
    return std::nullopt;
  }

  void commit(int k, const Candidate& c) {
    auto& t = out_.trajectories[k].samples;
    t.insert(t.end(), c.samples.begin(), c.samples.end());
    auto& path = out_.paths[k];
    path.insert(path.end(), c.path.begin() + 1, c.path.end());
    stops_[static_cast<std::size_t>(k)].push_back({t.size(), path.size()});
    if (observer_) observer_->pieceAccepted(k, c.path, c.samples);
  }

  bool reachesGoal(const Candidate& c, const Eigen::Vector2d& goal) const {
    const Eigen::Vector2d end = c.samples.empty() ? c.path.front() : xyOf(c.samples.back());
    return (end - goal).norm() <= p_.controller.acceptanceRadius + 0.1;
  }

  // Keeps later tries out of `zone`, unless that would wall in the start or the goal (then only
  // the seed changes).
  void keepOutOf(int k, const Eigen::Vector2d& goal, const KeepOutZone& zone,
                 std::vector<KeepOutZone>& keepOut) const {
    if ((here(k) - zone.centre).norm() > zone.radius && (goal - zone.centre).norm() > zone.radius)
      keepOut.push_back(zone);
  }

  std::string conflictNote(const Conflict& c) const {
    char buf[200];
    std::snprintf(buf, sizeof buf, "within %.2f m of rover %d, under safety_distance %.2f m, at t = %.1f s (%.2f, %.2f)",
                  c.distance, c.other + 1, p_.safetyDistance, c.time, c.position.x(), c.position.y());
    return buf;
  }

  // One piece of a leg, the same loop for every policy: tries with new seeds, each keeping out
  // of where the earlier ones came too close or tilted; each within-limit try started at the
  // policy's delays; then the policy's waits; then the caller skips the leg.
  Outcome runPiece(int k, int i, int piece, const Eigen::Vector2d& goal, LegRecord& rec,
                   bool& reachedGoal) {
    const bool lastLeg = i + 1 == static_cast<int>(tasks_[k].legs.size());
    std::vector<KeepOutZone> keepOut;
    std::optional<Candidate> firstTry;  // the first try within the attitude check
    std::optional<Conflict> conflict;
    std::optional<PathStatus> noPath;
    int zoneTries = 0;       // tries refused for a sample in a keep-out zone
    int unturnableEnds = 0;  // tries refused for ending where the rover cannot turn
    std::optional<Tilt> leastTilt;  // of the tries refused for tilting past the attitude check
    std::size_t zonesBefore = 0;  // keep-out zones of the previous try
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
      if (!path.hasPath() || path.waypoints.size() < 2) {
        noPath = path.status;
        // Without keep-out zones a new seed cannot turn an invalid start or goal valid.
        if (keepOut.empty() && path.status == PathStatus::InvalidGoal && policy_.invalidGoalEndsPiece()) {
          rec.note = "no path: invalid_goal (not on ground a rover may stop on)";
          return Outcome::InvalidGoal;
        }
        if (keepOut.empty() &&
            (path.status == PathStatus::InvalidGoal || path.status == PathStatus::InvalidStart))
          break;
        continue;
      }
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

  // The rover stays where its last leg left it for the rest of the mission. If a higher-priority
  // rover still moving would pass too close, it drives out of the way (ours).
  // It also drives off when it stands near a goal or fixed point of a lower-priority rover's
  // leg: parked there for good, it would block that leg for ever (hybrid missions on the default
  // map: 14 of 18 skipped legs were the team mates' last coverage moves round the first rover's
  // end).
  void park(int k) {
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

  // Every committed sample of rover k was checked against the traffic table, but the rest of the
  // mission after its last one only as far as the policy checks it: a leg for the dwell, then
  // park() — which finds no spot near a map edge or a wall, or runs out of moves (issue 25: a
  // rover parked at the east edge of the Gale patch, run over four times by two higher-priority
  // rovers that came by later). The rover then stops at the latest end of a committed move where
  // it may stand for the rest of the mission — its start at worst, where every rover planned
  // earlier kept clear of it — and the moves after it are undone: their legs end there, short or
  // skipped for the conflict. So a finished rover never stands in a planned rover's way, by
  // construction. (The observer was told of the undone pieces as they came; the result is
  // final.)
  void stopWhereSafe(int k) {
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

  // Cuts rover k back to its stop `stop` (stopWhereSafe): the legs after it end there, short or
  // skipped for `conflict`; the moves aside after it are dropped. Keeps the leg records as they
  // were in legsBefore_, to undo a cut.
  void cutAt(int k, std::size_t stop, const Conflict& conflict) {
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


  // Drives rover k to a spot it can reach and stand at without a conflict, clear of later rovers'
  // goals, and commits the move; returns when it started (nullopt: no spot works). Candidates:
  // back along its own trajectory (ground it has driven, so reachable even in a dead end), every
  // 2 m, then rings of growing radius round it; within the attitude limit if at all possible (a
  // collision is worse than a tilt, so a second pass accepts a move that exceeds it, reported as
  // an exceedance). `move` numbers the calls for a rover (it salts the seeds).
  // Where it looks and how hard: the policy's AsideSearch (paper: 40 m back, 7 rings of 8, an
  // RRT* call per spot, a spot clear for good; timed: 200 m back, 9 rings of 16, the traffic
  // table read first).
  std::optional<double> moveAside(int k, int move) {
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

  // Rover k tilts when it turns in place where it stands (a stop on ground steeper than the limit
  // in some direction): drives straight out, nearest its heading first (every 10° round), 0.5 to
  // 1.5 m, to ground where it may stop and turn, without tilting, entering a zone or a conflict
  // (delayed like any try). The planner's edge check is not asked: its limit is the planning
  // one (14°), and the rover stands on steeper ground already; the simulated drive is the judge.
  // Commits the move; false when no heading works.
  bool escapeTurn(int k, int i, int salt) {
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

  // `p` is closer than the safety distance plus both acceptance circles to a goal or fixed point
  // of a lower-priority rover's leg (the spacing the task builder keeps between goals).
  bool blocksLaterGoal(int k, const Eigen::Vector2d& p) const {
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

  void runLeg(int k, int i) {
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

  const std::vector<RoverTask>& tasks_;
  const std::vector<int> order_;  // the order the rovers are planned in (departureOrder)
  const int firstRound_;          // how many of order_ leave in its first round
  std::vector<int> rank_;         // per rover, its place in order_
  const LegPlanner& planner_;
  const LegSimulator& simulator_;
  const ConflictPolicy& policy_;
  const CoordinationParams& p_;
  const std::uint64_t seed_;
  CoordinationObserver* observer_;
  const CancelToken* cancel_;
  const double period_;
  std::unique_ptr<PlanAhead> ahead_;
  std::vector<std::size_t> firstJob_;  // per rover, the index of its first leg's job
  // Per rover, the samples and waypoints it had after each committed move (its start first):
  // where stopWhereSafe may cut it.
  struct Stop {
    std::size_t samples = 0, path = 0;
  };
  std::vector<std::vector<Stop>> stops_;
  std::vector<LegRecord> legsBefore_;  // cutAt: the leg records before the last cut
  CoordinationResult out_;
  TrafficTable traffic_;
  // The last piece was skipped for a conflict in its first second: no try nor delay got the
  // rover away from where it stands (runPiece sets it, runLeg reads it).
  bool boxedIn_ = false;  // the rovers done so far; the others standing at their starts
  int legsDone_ = 0;
  int legsTotal_ = 0;
};

}  // namespace

CoordinationResult coordinateWith(const std::vector<RoverTask>& tasks, const LegPlanner& planner,
                                  const LegSimulator& simulator, const ConflictPolicy& policy,
                                  const CoordinationParams& params, std::uint64_t seed,
                                  CoordinationObserver* observer, const CancelToken* cancel,
                                  const planning::PassableGround& passable) {
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
  std::vector<Eigen::Vector2d> starts;
  for (const RoverTask& t : tasks) starts.emplace_back(t.start.x, t.start.y);
  planning::Departure departure = planning::departureOrder(starts, params.safetyDistance, passable);
  if (!departure.boxedIn.empty()) {
    const std::string field = "rovers[" + std::to_string(departure.boxedIn.front()) + "]";
    throw Error(ErrorCode::InvalidInput, field,
                field + ": start is boxed in: no way out past the other rovers' starts keeping the safety distance "
                        "(+ " + oneDecimal(planning::kDepartureMargin) + " m)");
  }
  return Coordinator(tasks, std::move(departure.order), departure.firstRound, planner, simulator, policy, params, seed, observer,
                     cancel)
      .run();
}

}  // namespace rover::team
