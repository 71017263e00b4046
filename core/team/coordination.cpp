#include "core/team/coordination.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/common/error.hpp"
#include "core/common/parallel.hpp"
#include "core/common/random.hpp"

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
}

const char* coordinationModeName(CoordinationMode m) {
  switch (m) {
    case CoordinationMode::Timed:
      return "timed";
    case CoordinationMode::Paper:
      return "paper";
  }
  return "unknown";
}

const char* legReasonName(LegReason r) {
  switch (r) {
    case LegReason::None:
      return "none";
    case LegReason::InvalidGoal:
      return "invalid_goal";
    case LegReason::NoPath:
      return "no_path";
    case LegReason::Steep:
      return "steep";
    case LegReason::Conflict:
      return "conflict";
    case LegReason::PiecesExhausted:
      return "pieces_exhausted";
  }
  return "unknown";
}

namespace {
double edgeResolutionFor(const terrain::Dem& dem, const RrtParams& rrt) {
  const GridGeometry& g = dem.geometry();
  return rrt.edgeResolution > 0 ? rrt.edgeResolution : 0.25 * std::min(g.cellWidth, g.cellHeight);
}
}  // namespace

TraversalLattice makeLattice(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                             const CoordinationParams& params) {
  return TraversalLattice(dem, classes, params.rrt.attitudeLimit, edgeResolutionFor(dem, params.rrt),
                          params.weights, params.rrt.range, params.threads);
}

const char* legStatusName(LegStatus s) {
  switch (s) {
    case LegStatus::Reached:
      return "reached";
    case LegStatus::Short:
      return "short";
    case LegStatus::Skipped:
      return "skipped";
  }
  return "unknown";
}

namespace {

Eigen::Vector2d xyOf(const TrajectorySample& s) { return {s.x, s.y}; }

// Position at sample index i: before the start the rover waits at its first sample, after the
// end it is parked at its last (SPEC §3.4 as implemented here: parked rovers are obstacles).
Eigen::Vector2d positionAtIndex(const Trajectory& t, std::size_t i) {
  return xyOf(t.samples[std::min(i, t.samples.size() - 1)]);
}

std::uint64_t seedFor(std::uint64_t seed, int rover, int leg, int piece, int attempt) {
  std::uint64_t s = deriveSeed(seed, static_cast<std::uint64_t>(rover));
  s = deriveSeed(s, static_cast<std::uint64_t>(leg));
  s = deriveSeed(s, static_cast<std::uint64_t>(piece));
  return deriveSeed(s, static_cast<std::uint64_t>(attempt));
}

Eigen::Vector2d legGoal(const Leg& leg) { return leg.via.empty() ? leg.goal : leg.via.back(); }

class Coordinator {
 public:
  Coordinator(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
              const std::vector<RoverTask>& tasks, const CoordinationParams& params,
              std::uint64_t seed, CoordinationObserver* observer, const CancelToken* cancel,
              const TraversalLattice* lattice)
      : dem_(dem),
        classes_(classes),
        tasks_(tasks),
        p_(params),
        seed_(seed),
        observer_(observer),
        cancel_(cancel),
        period_(params.controller.samplePeriod),
        wholeMap_(dem, classes, mapBounds(dem), params.rrt.attitudeLimit, edgeResolution()),
        lattice_(lattice) {}

  CoordinationResult run() {
    const int n = static_cast<int>(tasks_.size());
    out_.trajectories.resize(n);
    out_.paths.resize(n);
    for (int k = 0; k < n; ++k) startRover(k);
    for (const auto& t : tasks_) legsTotal_ += static_cast<int>(t.legs.size());
    planAhead();
    for (int k = 0; k < n && !out_.cancelled; ++k) {
      for (int i = 0; i < static_cast<int>(tasks_[k].legs.size()); ++i) {
        runLeg(k, i);
        if (out_.cancelled) break;
      }
      if (!out_.cancelled) park(k);
    }
    out_.conflicts = checkSeparation(out_.trajectories, p_.safetyDistance).conflicts;
    return std::move(out_);
  }

 private:
  enum class Outcome { Accepted, Skipped, NoPath, InvalidGoal, Steep, Cancelled };

  bool timed() const { return p_.mode == CoordinationMode::Timed && lattice_; }

  // s a leg is checked standing at its end. Paper mode: dwell_check, since its next leg starts at
  // once or only after whole wait steps. Timed: at most the time to get going and drive out of
  // the safety distance (1 s + safety / nominal speed, 4.3 s by default) — the next leg's delays
  // check the rover standing there themselves, sample by sample, for as long as it stands; a
  // longer dwell only refused arrivals a short stop makes safely (measured on the default map,
  // seeds 1–3: 9 of 960 legs skipped with 10 s, 6 with 4.5 s; with 0.5 s a rover could arrive
  // where it had no time to get away, 7 skipped on seed 2).
  double dwell() const {
    if (!timed()) return p_.dwellCheck;
    return std::min(p_.dwellCheck, p_.safetyDistance / p_.controller.nominalSpeed + 1.0);
  }

  // One planning problem of a leg. Paper: RRT* in the start/goal box. Timed: a guide path on the
  // lattice (keeping out of the keep-out zones), RRT* in the corridor around it, and the guide
  // itself when RRT* ends short — it is valid by construction, so a leg to a reachable goal
  // reaches it. Without a guide (goal cell unreachable) the boxed RRT* still gets its chance.
  PathResult planLeg(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal,
                     const RrtParams& rrt, const std::vector<KeepOutZone>& keepOut) const {
    if (!timed()) return planPath(dem_, classes_, from, heading, goal, rrt, p_.weights, cancel_, keepOut);
    auto guide = lattice_->guidePath(from, goal, keepOut);
    if (!guide) return planPath(dem_, classes_, from, heading, goal, rrt, p_.weights, cancel_, keepOut);
    // The corridor holds the paper's box too: never less room than paper mode, and on a straight
    // leg the same tree density (a corridor alone packs the 1250 vertices tighter, which costs
    // rewiring time for nothing).
    const SearchBounds box = searchBounds(dem_.geometry(), from, goal, rrt.clearance);
    const Corridor corridor = lattice_->corridor(*guide, p_.corridorRadius, &box);
    PathResult r = planPath(dem_, classes_, from, heading, goal, rrt, p_.weights, cancel_, keepOut,
                            &corridor);
    if (r.status == PathStatus::Exact || r.status == PathStatus::Cancelled ||
        r.status == PathStatus::InvalidGoal)
      return r;
    PathResult g;
    g.status = PathStatus::Exact;
    g.waypoints = std::move(*guide);
    g.cost = pathCost(lattice_->model(), g.waypoints, heading, p_.weights, false);
    g.costWithTurns = pathCost(lattice_->model(), g.waypoints, heading, p_.weights, true);
    g.vertices = r.vertices;
    g.iterations = r.iterations;
    return g;
  }

  struct Candidate {
    std::vector<Eigen::Vector2d> path;         // waypoints, the rover's position first
    std::vector<TrajectorySample> samples;     // new samples (waits, then driving)
    bool reached = false;                      // the simulation entered the last waypoint's circle
  };

  struct Ahead {
    bool planned = false;
    Eigen::Vector2d start{0, 0};
    PathResult path;
  };

  static SearchBounds mapBounds(const terrain::Dem& dem) {
    const GridGeometry& g = dem.geometry();
    return {{0, 0}, {g.widthMetres(), g.heightMetres()}};
  }
  double edgeResolution() const {
    const GridGeometry& g = dem_.geometry();
    return p_.rrt.edgeResolution > 0 ? p_.rrt.edgeResolution
                                     : 0.25 * std::min(g.cellWidth, g.cellHeight);
  }
  bool cancelled() const { return cancel_ && cancel_->cancelled(); }
  const TrajectorySample& last(int k) const { return out_.trajectories[k].samples.back(); }
  Eigen::Vector2d here(int k) const { return xyOf(last(k)); }

  // The first sample: the rover at rest on its start (simulate with the start as its only
  // waypoint records exactly that, with the terrain height and attitude).
  void startRover(int k) {
    const Pose& s = tasks_[k].start;
    Trajectory t;
    try {
      t = simulate(dem_, {Eigen::Vector2d(s.x, s.y)}, s, 0.0, p_.model, p_.controller, p_.slip);
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
  }

  // Plans every RRT* leg from its nominal start in parallel (the legs are independent problems).
  void planAhead() {
    ahead_.resize(tasks_.size());
    struct Job {
      int rover, leg;
      Eigen::Vector2d start;
      double heading;
    };
    std::vector<Job> jobs;
    for (int k = 0; k < static_cast<int>(tasks_.size()); ++k) {
      const RoverTask& task = tasks_[k];
      ahead_[k].resize(task.legs.size());
      Eigen::Vector2d start(task.start.x, task.start.y);
      double heading = task.start.heading;
      for (int i = 0; i < static_cast<int>(task.legs.size()); ++i) {
        const Eigen::Vector2d goal = legGoal(task.legs[i]);
        if (task.legs[i].via.empty()) jobs.push_back({k, i, start, heading});
        if ((goal - start).norm() > 1e-9) heading = std::atan2(goal.y() - start.y(), goal.x() - start.x());
        start = goal;
      }
    }
    parallelFor(jobs.size(), p_.threads, [&](std::size_t j) {
      const Job& job = jobs[j];
      RrtParams rrt = p_.rrt;
      rrt.seed = seedFor(seed_, job.rover, job.leg, 0, 0);
      Ahead& a = ahead_[job.rover][job.leg];
      a.start = job.start;
      a.path = planLeg(job.start, job.heading, tasks_[job.rover].legs[job.leg].goal, rrt, {});
      a.planned = true;
    });
    out_.rrtCalls += static_cast<int>(jobs.size());
  }

  // The path of one try: the fixed points of a via leg (first try, if every edge is valid), the
  // path planned ahead (first try, if the rover stopped where that plan started), else RRT* now.
  PathResult tryPath(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                     const std::vector<KeepOutZone>& keepOut) {
    const Leg& leg = tasks_[k].legs[i];
    const Eigen::Vector2d from = here(k);
    if (attempt == 0 && piece == 0 && !leg.via.empty()) {
      PathResult r;
      r.waypoints.push_back(from);
      bool valid = true;
      for (const auto& v : leg.via) {
        valid = valid && wholeMap_.edgeValid(r.waypoints.back(), v);
        r.waypoints.push_back(v);
      }
      if (valid) {
        r.status = PathStatus::Exact;
        return r;
      }
    }
    if (attempt == 0 && piece == 0 && leg.via.empty()) {
      const Ahead& a = ahead_[k][i];
      if (a.planned && a.path.hasPath() &&
          (a.start - from).norm() <= p_.controller.acceptanceRadius + 0.05) {
        PathResult r = a.path;
        r.waypoints.front() = from;
        return r;
      }
    }
    RrtParams rrt = p_.rrt;
    rrt.seed = seedFor(seed_, k, i, piece, attempt);
    ++out_.rrtCalls;
    return planLeg(from, last(k).heading, goal, rrt, keepOut);
  }

  Candidate simulateTry(int k, const std::vector<Eigen::Vector2d>& path, int waitTicks,
                        std::uint64_t slipSeed) {
    const TrajectorySample origin = last(k);
    const std::size_t base = out_.trajectories[k].samples.size() - 1;  // index of `origin`
    Candidate c;
    c.path = path;
    for (int j = 1; j <= waitTicks; ++j) {
      TrajectorySample s = origin;
      s.time = static_cast<double>(base + j) * period_;
      s.speed = 0;
      c.samples.push_back(s);
    }
    std::vector<Eigen::Vector2d> waypoints(path.begin() + 1, path.end());
    if (waypoints.empty()) {
      c.reached = true;
      return c;
    }
    SlipParams slip = p_.slip;
    slip.seed = slipSeed;
    const std::size_t startIndex = base + waitTicks;
    Trajectory sim = simulate(dem_, waypoints, {origin.x, origin.y, origin.heading},
                              static_cast<double>(startIndex) * period_, p_.model, p_.controller,
                              slip, cancel_);
    for (std::size_t m = 1; m < sim.samples.size(); ++m) {
      TrajectorySample s = sim.samples[m];
      s.time = static_cast<double>(startIndex + m) * period_;
      s.distance += origin.distance;
      c.samples.push_back(s);
    }
    c.reached = sim.status == SimStatus::Reached;
    return c;
  }

  // The first sample of `samples` (appended to rover k's trajectory) closer than the safety
  // distance to a higher-priority rover; with `parkedAfter`, also rover k parked at its last
  // position for as long as any higher-priority rover still moves.
  std::optional<Conflict> firstConflict(int k, const std::vector<TrajectorySample>& samples,
                                        bool parkedForGood) const {
    const auto& trajectories = out_.trajectories;
    const std::size_t base = trajectories[k].samples.size();
    auto check = [&](std::size_t idx, const Eigen::Vector2d& p) -> std::optional<Conflict> {
      for (int j = 0; j < k; ++j) {
        const Eigen::Vector2d o = positionAtIndex(trajectories[j], idx);
        const double d = (p - o).norm();
        if (d < p_.safetyDistance)
          return Conflict{k, j, static_cast<double>(idx) * period_, 0.0, d, p, o};
      }
      return std::nullopt;
    };
    for (std::size_t m = 0; m < samples.size(); ++m)
      if (auto c = check(base + m, xyOf(samples[m]))) return c;
    // Standing at the end: for good after the last leg, else for the dwell check.
    std::size_t end = 0;
    for (int j = 0; j < k; ++j) end = std::max(end, trajectories[j].samples.size());
    const std::size_t from = base + samples.size();
    if (!parkedForGood)
      end = std::min(end, from + static_cast<std::size_t>(std::lround(dwell() / period_)));
    const Eigen::Vector2d p = samples.empty() ? here(k) : xyOf(samples.back());
    for (std::size_t idx = from; idx < end; ++idx)
      if (auto c = check(idx, p)) return c;
    return std::nullopt;
  }

  // The first sample with |roll| or |pitch| above the attitude check, if any.
  std::optional<Eigen::Vector2d> firstExceedance(const std::vector<TrajectorySample>& samples) const {
    if (!(p_.attitudeCheck > 0)) return std::nullopt;
    for (const auto& s : samples)
      if (std::abs(s.roll) > p_.attitudeCheck || std::abs(s.pitch) > p_.attitudeCheck)
        return xyOf(s);
    return std::nullopt;
  }

  void commit(int k, const Candidate& c) {
    auto& t = out_.trajectories[k].samples;
    t.insert(t.end(), c.samples.begin(), c.samples.end());
    auto& path = out_.paths[k];
    path.insert(path.end(), c.path.begin() + 1, c.path.end());
    if (observer_) observer_->pieceAccepted(k, c.path, c.samples);
  }

  // One piece of a leg: tries with new seeds (each keeping out of the earlier conflicts), then
  // waits, then gives up (the caller skips the leg).
  Outcome runPiece(int k, int i, int piece, const Eigen::Vector2d& goal, LegRecord& rec,
                   bool& reachedGoal) {
    const bool lastLeg = i + 1 == static_cast<int>(tasks_[k].legs.size());
    std::vector<KeepOutZone> keepOut;
    std::optional<Candidate> firstTry;
    std::optional<Conflict> conflict;
    std::string noPath;
    for (int attempt = 0; attempt <= p_.maxReplans; ++attempt) {
      if (cancelled()) return Outcome::Cancelled;
      if (attempt > 0) {
        ++rec.replans;
        ++out_.replans;
      }
      PathResult path = tryPath(k, i, piece, attempt, goal, keepOut);
      if (path.status == PathStatus::Cancelled) return Outcome::Cancelled;
      if (!path.hasPath() || path.waypoints.size() < 2) {
        noPath = pathStatusName(path.status);
        // Without keep-out zones a new seed cannot turn an invalid start or goal valid.
        const bool hopeless = path.status == PathStatus::InvalidGoal ||
                              path.status == PathStatus::InvalidStart;
        if (keepOut.empty() && hopeless) break;
        continue;
      }
      Candidate c = simulateTry(k, path.waypoints, 0, seedFor(deriveSeed(seed_ ^ 0x51ee5ull, p_.slip.seed), k, i, piece, attempt));
      if (cancelled()) return Outcome::Cancelled;
      // The leg's last piece decides whether the rover parks here for good.
      conflict = firstConflict(k, c.samples, lastLeg && reachesGoal(c, goal));
      const std::optional<Eigen::Vector2d> steep = firstExceedance(c.samples);
      if (!conflict && !steep) {
        reachedGoal = path.status == PathStatus::Exact && c.reached;
        commit(k, c);
        return Outcome::Accepted;
      }
      // Waiting can only help a try that is within the attitude limit.
      if (!firstTry && !steep) firstTry = c;
      // A conflict in the first second: no other path can dodge it, only waiting can.
      if (conflict && conflict->time - last(k).time < 1.0) break;
      // Keep out of where the other rover was (or where the simulated rover tilted past the
      // limit), unless that would wall in the start or the goal (then only the seed changes).
      const KeepOutZone zone{conflict ? conflict->otherPosition : *steep,
                             conflict ? p_.keepOutRadius : 0.5};
      if ((here(k) - zone.centre).norm() > zone.radius && (goal - zone.centre).norm() > zone.radius)
        keepOut.push_back(zone);
    }
    if (!firstTry) {
      rec.note = noPath.empty() ? "every try tilts past the attitude limit" : "no path: " + noPath;
      if (noPath.empty()) return Outcome::Steep;
      return noPath == pathStatusName(PathStatus::InvalidGoal) ? Outcome::InvalidGoal
                                                               : Outcome::NoPath;
    }
    for (int w = 1; w <= p_.maxWaits; ++w) {
      if (cancelled()) return Outcome::Cancelled;
      const int ticks = static_cast<int>(std::lround(w * p_.waitStep / period_));
      Candidate c = simulateTry(k, firstTry->path, ticks, seedFor(deriveSeed(seed_ ^ 0x3a17ull, p_.slip.seed), k, i, piece, w));
      conflict = firstConflict(k, c.samples, lastLeg && reachesGoal(c, goal));
      if (!conflict && !firstExceedance(c.samples)) {
        rec.waits = w;
        out_.waits += w;
        reachedGoal = c.reached && (firstTry->path.back() - goal).norm() < 1e-9;
        commit(k, c);
        return Outcome::Accepted;
      }
    }
    if (!conflict) {
      rec.note = "no clear try";
      return Outcome::Skipped;
    }
    char buf[160];
    std::snprintf(buf, sizeof buf, "within %.2f m of rover %d at t = %.1f s (%.2f, %.2f)",
                  conflict->distance, conflict->other, conflict->time, conflict->position.x(),
                  conflict->position.y());
    rec.note = buf;
    return Outcome::Skipped;
  }

  // `c` started `ticks` samples later: the rover stands where it is meanwhile. The terrain does
  // not change, so the simulated motion is the same, only later.
  Candidate delayed(int k, const Candidate& c, int ticks) const {
    if (ticks == 0) return c;
    const TrajectorySample origin = last(k);
    const std::size_t base = out_.trajectories[k].samples.size() - 1;
    Candidate d;
    d.path = c.path;
    d.reached = c.reached;
    d.samples.reserve(c.samples.size() + static_cast<std::size_t>(ticks));
    for (int j = 1; j <= ticks; ++j) {
      TrajectorySample s = origin;
      s.time = static_cast<double>(base + j) * period_;
      s.speed = 0;
      d.samples.push_back(s);
    }
    for (TrajectorySample s : c.samples) {
      s.time += ticks * period_;
      d.samples.push_back(s);
    }
    return d;
  }

  // Timed mode's piece: each try is simulated once, then started at the first delay (0, δ, 2δ,
  // … up to max_waits × wait_step) at which it keeps the safety distance from every committed
  // trajectory at every 10 Hz sample (and standing at its end, as in paper mode). Only when no
  // delay clears it is the leg re-planned, keeping out of where the other rover was.
  Outcome runPieceTimed(int k, int i, int piece, const Eigen::Vector2d& goal, LegRecord& rec,
                        bool& reachedGoal) {
    const bool lastLeg = i + 1 == static_cast<int>(tasks_[k].legs.size());
    const int step = std::max(1, static_cast<int>(std::lround(p_.delayStep / period_)));
    const int maxTicks = static_cast<int>(std::lround(p_.maxWaits * p_.waitStep / period_));
    std::vector<KeepOutZone> keepOut;
    std::optional<Conflict> conflict;
    bool withinLimit = false;
    PathStatus noPath = PathStatus::Exact;
    for (int attempt = 0; attempt <= p_.maxReplans; ++attempt) {
      if (cancelled()) return Outcome::Cancelled;
      if (attempt > 0) {
        ++rec.replans;
        ++out_.replans;
      }
      PathResult path = tryPath(k, i, piece, attempt, goal, keepOut);
      if (path.status == PathStatus::Cancelled) return Outcome::Cancelled;
      if (!path.hasPath() || path.waypoints.size() < 2) {
        noPath = path.status;
        if (keepOut.empty() && path.status == PathStatus::InvalidGoal) {
          rec.note = "no path: invalid_goal (not on ground a rover may stop on)";
          return Outcome::InvalidGoal;
        }
        if (keepOut.empty() && path.status == PathStatus::InvalidStart) break;
        continue;
      }
      const Candidate c0 = simulateTry(
          k, path.waypoints, 0,
          seedFor(deriveSeed(seed_ ^ 0x51ee5ull, p_.slip.seed), k, i, piece, attempt));
      if (cancelled()) return Outcome::Cancelled;
      if (const auto steep = firstExceedance(c0.samples)) {
        if ((here(k) - *steep).norm() > 0.5 && (goal - *steep).norm() > 0.5)
          keepOut.push_back({*steep, 0.5});
        continue;
      }
      withinLimit = true;
      const bool parks = lastLeg && reachesGoal(c0, goal);
      std::optional<Conflict> first;
      for (int ticks = 0; ticks <= maxTicks; ticks += step) {
        Candidate c = delayed(k, c0, ticks);
        conflict = firstConflict(k, c.samples, parks);
        if (!first) first = conflict;
        if (conflict) continue;
        if (ticks > 0) {
          ++rec.waits;
          ++out_.waits;
          rec.waitTime += ticks * period_;
        }
        reachedGoal = path.status == PathStatus::Exact && c.reached;
        commit(k, c);
        return Outcome::Accepted;
      }
      conflict = first;
      const KeepOutZone zone{first->otherPosition, p_.keepOutRadius};
      if ((here(k) - zone.centre).norm() > zone.radius && (goal - zone.centre).norm() > zone.radius)
        keepOut.push_back(zone);
    }
    if (!withinLimit) {
      rec.note = noPath != PathStatus::Exact ? std::string("no path: ") + pathStatusName(noPath)
                                             : "every try tilts past the attitude limit";
      return noPath != PathStatus::Exact ? Outcome::NoPath : Outcome::Steep;
    }
    char buf[160];
    std::snprintf(buf, sizeof buf, "within %.2f m of rover %d at t = %.1f s (%.2f, %.2f)",
                  conflict->distance, conflict->other, conflict->time, conflict->position.x(),
                  conflict->position.y());
    rec.note = buf;
    return Outcome::Skipped;
  }

  bool reachesGoal(const Candidate& c, const Eigen::Vector2d& goal) const {
    const Eigen::Vector2d end = c.samples.empty() ? c.path.front() : xyOf(c.samples.back());
    return (end - goal).norm() <= p_.controller.acceptanceRadius + 0.1;
  }

  // The rover stays where its last leg left it for the rest of the mission. If a higher-priority
  // rover still moving would pass too close, it drives out of the way (ours): to the first spot,
  // in rings of growing radius around it, that it can reach and stay at without a conflict.
  void park(int k) {
    if (!firstConflict(k, {}, true)) return;
    const Eigen::Vector2d from = here(k);
    // Candidates: first back along its own trajectory (ground it has driven, so reachable even
    // in a dead end), every 2 m up to 40 m; then rings of growing radius around it.
    std::vector<Eigen::Vector2d> spots;
    const auto& samples = out_.trajectories[k].samples;
    const double end = samples.back().distance;
    double next = 2.0;
    for (auto it = samples.rbegin(); it != samples.rend() && next <= 40.0; ++it) {
      if (end - it->distance < next) continue;
      spots.emplace_back(it->x, it->y);
      next += 2.0;
    }
    for (double radius : {1.5, 2.5, 3.5, 5.0, 7.0})
      for (int d = 0; d < 8; ++d) {
        const double a = d * std::numbers::pi / 4;
        spots.push_back(from + radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
      }
    // Within the attitude limit if at all possible; a collision is worse than a tilt, so the
    // second pass accepts a move that exceeds it (reported as an exceedance).
    int attempt = 0;
    for (int pass = 0; pass < 2; ++pass)
    for (const Eigen::Vector2d& spot : spots) {
      if (cancelled()) return;
      if (!wholeMap_.turnValid(spot)) continue;
      RrtParams rrt = p_.rrt;
      rrt.seed = seedFor(seed_ ^ 0x9a4cull, k, attempt, 0, 0);
      ++attempt;
      ++out_.rrtCalls;
      PathResult path = planLeg(from, last(k).heading, spot, rrt, {});
      if (path.status != PathStatus::Exact || path.waypoints.size() < 2) continue;
      Candidate c = simulateTry(k, path.waypoints, 0, seedFor(seed_ ^ 0x9a4dull, k, attempt, 0, 0));
      if (!c.reached || firstConflict(k, c.samples, true) || (pass == 0 && firstExceedance(c.samples)))
        continue;
      commit(k, c);
      LegRecord rec;
      rec.rover = k;
      rec.leg = static_cast<int>(tasks_[k].legs.size());
      rec.startTime = c.samples.front().time;
      rec.endTime = last(k).time;
      rec.pieces = 1;
      rec.note = "parked out of the way";
      out_.legs.push_back(rec);
      return;
    }
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
    for (int piece = 0; piece < p_.maxPieces; ++piece) {
      const double before = (here(k) - goal).norm();
      if (before <= p_.controller.acceptanceRadius) {
        rec.status = LegStatus::Reached;
        break;
      }
      bool reached = false;
      const Outcome o = timed() ? runPieceTimed(k, i, piece, goal, rec, reached)
                                : runPiece(k, i, piece, goal, rec, reached);
      if (o == Outcome::Cancelled) {
        out_.cancelled = true;
        return;
      }
      if (o == Outcome::Skipped) {
        rec.status = LegStatus::Skipped;
        rec.reason = LegReason::Conflict;
        break;
      }
      if (o == Outcome::InvalidGoal) {
        // A goal off passable ground is skipped outright, not "short" (paper mode: only when no
        // piece moved the rover; the same when the first piece already finds it invalid).
        if (rec.pieces == 0) rec.status = LegStatus::Skipped;
        rec.reason = LegReason::InvalidGoal;
        break;
      }
      if (o == Outcome::NoPath || o == Outcome::Steep) {  // Short, with the note
        rec.reason = o == Outcome::NoPath ? LegReason::NoPath : LegReason::Steep;
        break;
      }
      ++rec.pieces;
      if (reached) {
        rec.status = LegStatus::Reached;
        break;
      }
      if ((here(k) - goal).norm() > before - 0.25) {  // no progress: stop chaining
        rec.note = "the tree ends short of the goal and makes no progress";
        rec.reason = LegReason::NoPath;
        break;
      }
      if (piece + 1 == p_.maxPieces) {
        rec.note = "goal not reached after max_pieces RRT* pieces";
        rec.reason = LegReason::PiecesExhausted;
      }
    }
    if (rec.status == LegStatus::Reached) rec.reason = LegReason::None;
    rec.endTime = last(k).time;
    out_.legs.push_back(rec);
    ++legsDone_;
    if (observer_) observer_->legDone(rec, legsDone_, legsTotal_);
  }

  const terrain::Dem& dem_;
  const Raster<std::uint8_t>& classes_;
  const std::vector<RoverTask>& tasks_;
  const CoordinationParams& p_;
  const std::uint64_t seed_;
  CoordinationObserver* observer_;
  const CancelToken* cancel_;
  const double period_;
  TerrainEdgeModel wholeMap_;
  const TraversalLattice* lattice_;
  std::vector<std::vector<Ahead>> ahead_;
  CoordinationResult out_;
  int legsDone_ = 0;
  int legsTotal_ = 0;
};

}  // namespace

CoordinationResult coordinate(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                              const std::vector<RoverTask>& tasks,
                              const CoordinationParams& params, std::uint64_t seed,
                              CoordinationObserver* observer, const CancelToken* cancel,
                              const TraversalLattice* lattice) {
  params.validate();
  if (tasks.empty()) throw Error(ErrorCode::InvalidInput, "rovers", "rovers: none given");
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
  std::optional<TraversalLattice> own;
  if (params.mode == CoordinationMode::Timed && !lattice) {
    own.emplace(dem, classes, params.rrt.attitudeLimit, edgeResolutionFor(dem, params.rrt),
                params.weights, params.rrt.range, params.threads);
    lattice = &*own;
  }
  Coordinator c(dem, classes, tasks, params, seed, observer, cancel, lattice);
  return c.run();
}

SeparationReport checkSeparation(const std::vector<Trajectory>& trajectories, double safety) {
  SeparationReport r;
  r.minimumDistance = std::numeric_limits<double>::infinity();
  std::size_t end = 0;
  for (const auto& t : trajectories) {
    if (t.samples.empty()) throw Error(ErrorCode::InvalidInput, "trajectory", "a trajectory has no samples");
    end = std::max(end, t.samples.size());
  }
  const double period = trajectories.empty() ? 0.1 : trajectories.front().samplePeriod;
  for (std::size_t a = 0; a < trajectories.size(); ++a) {
    for (std::size_t b = a + 1; b < trajectories.size(); ++b) {
      std::optional<Conflict> open;
      for (std::size_t i = 0; i < end; ++i) {
        const Eigen::Vector2d pa = positionAtIndex(trajectories[a], i);
        const Eigen::Vector2d pb = positionAtIndex(trajectories[b], i);
        const double d = (pa - pb).norm();
        if (d < r.minimumDistance) {
          r.minimumDistance = d;
          r.minimumTime = static_cast<double>(i) * period;
          r.minimumPair[0] = static_cast<int>(a);
          r.minimumPair[1] = static_cast<int>(b);
        }
        if (d < safety) {
          if (!open) open = Conflict{static_cast<int>(b), static_cast<int>(a),
                                     static_cast<double>(i) * period, 0.0, d, pb, pa};
          open->distance = std::min(open->distance, d);
          open->duration = static_cast<double>(i) * period - open->time;
        } else if (open) {
          r.conflicts.push_back(*open);
          open.reset();
        }
      }
      if (open) r.conflicts.push_back(*open);
    }
  }
  std::sort(r.conflicts.begin(), r.conflicts.end(),
            [](const Conflict& x, const Conflict& y) { return x.time < y.time; });
  return r;
}

}  // namespace rover::team
