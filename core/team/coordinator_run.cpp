// The coordinator's set-up and run, its tries (planned ahead or now, simulated, delayed) and
// the checks of a try against the traffic table and the rover limits.
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

CoordinationResult Coordinator::run() {
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

std::uint64_t Coordinator::slipSeed(std::uint64_t salt, int k, int i, int piece, int attempt) const {
  return seedFor(deriveSeed(seed_ ^ salt, p_.slip.seed), k, i, piece, attempt);
}

void Coordinator::startRover(int k) {
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

void Coordinator::planAhead() {
  std::vector<PlanAhead::Job> jobs;
  for (int k = 0; k < static_cast<int>(tasks_.size()); ++k) {
    const RoverTask& task = tasks_[k];
    firstJob_.push_back(jobs.size());
    Eigen::Vector2d start(task.start.x, task.start.y);
    double heading = task.start.heading;
    for (int i = 0; i < static_cast<int>(task.legs.size()); ++i) {
      const Leg& leg = task.legs[i];
      const Eigen::Vector2d goal = legGoal(leg);
      jobs.push_back({start, heading, goal, seedFor(seed_, k, i, 0, 0), leg.via.empty() || !viaValid(start, leg),
                      standingZones(k, start, goal)});
      if ((goal - start).norm() > 1e-9) heading = std::atan2(goal.y() - start.y(), goal.x() - start.x());
      start = goal;
    }
  }
  const unsigned threads = p_.threads == 0 ? hardwareThreads() : p_.threads;
  ahead_ = std::make_unique<PlanAhead>(planner_, std::move(jobs), threads > 1 ? threads - 1 : 0, cancel_);
}

std::vector<KeepOutZone> Coordinator::standingZones(int k, const Eigen::Vector2d& from,
                                                    const Eigen::Vector2d& goal) const {
  std::vector<KeepOutZone> zones;
  const double radius = policy_.standingKeepOut();
  if (!(radius > 0)) return zones;
  for (std::size_t j = 0; j < tasks_.size(); ++j) {
    if (rank_[j] <= rank_[static_cast<std::size_t>(k)]) continue;  // planned before k, or k
    const Eigen::Vector2d at(tasks_[j].start.x, tasks_[j].start.y);
    if ((from - at).norm() > radius && (goal - at).norm() > radius) zones.push_back({at, radius});
  }
  return zones;
}

bool Coordinator::viaValid(const Eigen::Vector2d& from, const Leg& leg) const {
  Eigen::Vector2d a = from;
  for (const auto& v : leg.via) {
    if (!planner_.edgeValid(a, v)) return false;
    a = v;
  }
  return true;
}

PathResult Coordinator::tryPath(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
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

PlanAhead::Request Coordinator::replan(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                          const std::vector<KeepOutZone>& keepOut) const {
  return {here(k), last(k).heading, goal, seedFor(seed_, k, i, piece, attempt), keepOut};
}

void Coordinator::stand(int k, int ticks, std::vector<TrajectorySample>& samples) const {
  const TrajectorySample origin = last(k);
  const std::size_t base = out_.trajectories[k].samples.size() - 1;  // index of `origin`
  for (int j = 1; j <= ticks; ++j) {
    TrajectorySample s = origin;
    s.time = static_cast<double>(base + j) * period_;
    s.speed = 0;
    samples.push_back(s);
  }
}

Coordinator::Candidate Coordinator::simulateTry(int k, const std::vector<Eigen::Vector2d>& path, int waitTicks,
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

Coordinator::Candidate Coordinator::delayed(int k, const Candidate& c, int ticks) const {
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

std::optional<Conflict> Coordinator::firstConflict(int k, std::span<const TrajectorySample> samples, int ticks,
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

std::vector<int> Coordinator::startDelays(int k) const {
  std::vector<int> delays = policy_.startDelays();
  if (!policy_.recovers() || rank_[static_cast<std::size_t>(k)] < firstRound_ ||
      stops_[static_cast<std::size_t>(k)].size() > 1)
    return delays;
  const std::vector<int> more = delaysUntilTrafficEnds(k, delays.back());
  delays.insert(delays.end(), more.begin(), more.end());
  return delays;
}

std::vector<int> Coordinator::delaysUntilTrafficEnds(int k, int after) const {
  const int step = std::max(1, static_cast<int>(std::lround(p_.waitStep / period_)));
  const std::size_t now = out_.trajectories[k].samples.size();
  std::vector<int> delays;
  for (std::size_t t = static_cast<std::size_t>(after) + step; now + t < traffic_.end() + step; t += step)
    delays.push_back(static_cast<int>(t));
  return delays;
}

Coordinator::Tilt Coordinator::steepestTilt(const std::vector<TrajectorySample>& samples) {
  Tilt t;
  for (const auto& s : samples) {
    if (std::abs(s.roll) > t.angle) t = {std::abs(s.roll), false};
    if (std::abs(s.pitch) > t.angle) t = {std::abs(s.pitch), true};
  }
  return t;
}

std::string Coordinator::tiltNote(const char* what, const Tilt& reached, const char* reachedBy) const {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s tilts past attitude_check %.1f° (%s reached %.1f° %s)",
                what, p_.attitudeCheck * kDeg, reachedBy, reached.angle * kDeg, reached.pitch ? "pitch" : "roll");
  return buf;
}

std::optional<Eigen::Vector2d> Coordinator::firstExceedance(const std::vector<TrajectorySample>& samples) const {
  if (!(p_.attitudeCheck > 0)) return std::nullopt;
  for (const auto& s : samples)
    if (std::abs(s.roll) > p_.attitudeCheck || std::abs(s.pitch) > p_.attitudeCheck)
      return xyOf(s);
  return std::nullopt;
}

std::optional<Eigen::Vector2d> Coordinator::firstForbidden(const std::vector<TrajectorySample>& samples) const {
  for (const auto& s : samples)
    if (planner_.forbidden(xyOf(s))) return xyOf(s);
  return std::nullopt;
}

void Coordinator::commit(int k, const Candidate& c) {
  auto& t = out_.trajectories[k].samples;
  t.insert(t.end(), c.samples.begin(), c.samples.end());
  auto& path = out_.paths[k];
  path.insert(path.end(), c.path.begin() + 1, c.path.end());
  stops_[static_cast<std::size_t>(k)].push_back({t.size(), path.size()});
  if (observer_) observer_->pieceAccepted(k, c.path, c.samples);
}

bool Coordinator::reachesGoal(const Candidate& c, const Eigen::Vector2d& goal) const {
  const Eigen::Vector2d end = c.samples.empty() ? c.path.front() : xyOf(c.samples.back());
  return (end - goal).norm() <= p_.controller.acceptanceRadius + 0.1;
}

void Coordinator::keepOutOf(int k, const Eigen::Vector2d& goal, const KeepOutZone& zone,
               std::vector<KeepOutZone>& keepOut) const {
  if ((here(k) - zone.centre).norm() > zone.radius && (goal - zone.centre).norm() > zone.radius)
    keepOut.push_back(zone);
}

std::string Coordinator::conflictNote(const Conflict& c) const {
  char buf[200];
  std::snprintf(buf, sizeof buf, "within %.2f m of rover %d, under safety_distance %.2f m, at t = %.1f s (%.2f, %.2f)",
                c.distance, c.other + 1, p_.safetyDistance, c.time, c.position.x(), c.position.y());
  return buf;
}

}  // namespace rover::team::detail
