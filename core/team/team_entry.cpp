#include "core/team/team_entry.hpp"

#include <chrono>
#include <cmath>
#include <numbers>

#include "core/common/error.hpp"
#include "core/planning/mission_check.hpp"
#include "core/terrain/body.hpp"

namespace rover::team {

namespace {

using P = TeamPlannerParams;
constexpr double kDeg = std::numbers::pi / 180.0;

// Binds a key to a field reached through `field` (a generic lambda returning a reference, so the
// same accessor serves the getter on a const struct and the setter).
template <class F>
void addReal(ParamTable<P>& t, ParamInfo info, F field, double scale = 1.0) {
  t.add(
      std::move(info), [field, scale](const P& p) -> ParamValue { return field(p) / scale; },
      [field, scale](P& p, const ParamInfo& i, const ParamValue& v) {
        field(p) = paramAsReal(i, v) * scale;
      });
}
template <class F>
void addInt(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info),
      [field](const P& p) -> ParamValue { return static_cast<std::int64_t>(field(p)); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) {
        field(p) = static_cast<std::remove_reference_t<decltype(field(p))>>(paramAsInt(i, v));
      });
}
template <class F>
void addBool(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return static_cast<bool>(field(p)); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { field(p) = paramAsBool(i.key, v); });
}

// A flag whose parameter says the opposite of the field (parameters default to false).
template <class F>
void addInverted(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return !field(p); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { field(p) = !paramAsBool(i.key, v); });
}

ParamTable<P> buildTable() {
  ParamTable<P> t;
  // Route (SPEC §3.1).
  t.add(choiceParam("route", {"lhc_gw_conv", "lhc", "lawnmower"},
                    "Team route over the PDM: LHC_GW_CONV (paper 001), plain hill climbing without "
                    "global warming, or a boustrophedon lawnmower (baselines)."),
        [](const P& p) -> ParamValue { return std::string(routeMethodName(p.mission.routeMethod)); },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          const std::string s = paramAsChoice(i, v);
          p.mission.routeMethod = s == "lhc"         ? RouteMethod::Lhc
                                  : s == "lawnmower" ? RouteMethod::Lawnmower
                                                     : RouteMethod::LhcGwConv;
        });
  addInt(t, intParam("targets", 1, 10000, "targets", "Route length: search cells visited after the start (paper 001: 64)."),
         [](auto& p) -> auto& { return p.mission.route.targets; });
  addInt(t, intParam("warming_levels", 0, 1000, "", "Global-warming levels l of eq. 8 (C = p_max / l); 0 = plain hill climb."),
         [](auto& p) -> auto& { return p.mission.route.warmingLevels; });
  addInverted(t, boolParam("plain_tie_break", "Break hill-climb ties by the fixed neighbour order only, without the 3×3 box blur of eq. 6–7."),
              [](auto& p) -> auto& { return p.mission.route.convolutionTieBreak; });
  addReal(t, realParam("footprint_m", 0.25, 1000, "m", "Team footprint: the side of a search cell (paper 001: 5 m)."),
          [](auto& p) -> auto& { return p.mission.footprint; });
  addReal(t, realParam("sensing_diameter_m", 0.01, 100, "m", "Diameter of the disc each rover senses (paper 001: 1 m)."),
          [](auto& p) -> auto& { return p.mission.sensingDiameter; });
  addReal(t, realParam("high_risk_deg", 0.1, 90, "deg", "Traversability: slope from which a cell is high risk."),
          [](auto& p) -> auto& { return p.mission.traversability.highRiskDeg; });
  addReal(t, realParam("impassable_deg", 0.1, 90, "deg", "Traversability: slope from which a cell is impassable (never a target, never entered)."),
          [](auto& p) -> auto& { return p.mission.traversability.impassableDeg; });
  // Coordination (SPEC §3.4).
  t.add(choiceParam("coordination", {"timed", "paper"},
                    "timed (ours): RRT* in a corridor round a guide path on the whole map, conflicts "
                    "resolved by starting later (checked at 10 Hz), re-planning only as a fallback; "
                    "paper: paper 001's boxed RRT* and seed re-planning."),
        [](const P& p) -> ParamValue {
          return std::string(coordinationModeName(p.mission.coordination.mode));
        },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          p.mission.coordination.mode = paramAsChoice(i, v) == "paper" ? CoordinationMode::Paper
                                                                       : CoordinationMode::Timed;
        });
  addReal(t, realParam("corridor_radius", 0.5, 100, "m", "timed: RRT* samples within this distance of the leg's guide path."),
          [](auto& p) -> auto& { return p.mission.coordination.corridorRadius; });
  addReal(t, realParam("delay_step", 0.1, 3600, "s", "timed: delays tried before a re-plan are multiples of this, up to max_waits × wait_step."),
          [](auto& p) -> auto& { return p.mission.coordination.delayStep; });
  addReal(t, realParam("safety_distance", 0, 100, "m", "Two rovers closer than this collide (SPEC §3.4: 1 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.safetyDistance; });
  addInt(t, intParam("max_replans", 0, 1000, "", "Re-plans with a new seed before a rover waits (SPEC §3.4: 20)."),
         [](auto& p) -> auto& { return p.mission.coordination.maxReplans; });
  addReal(t, realParam("wait_step", 0.1, 3600, "s", "Each wait holds the rover this much longer before it tries again."),
          [](auto& p) -> auto& { return p.mission.coordination.waitStep; });
  addInt(t, intParam("max_waits", 0, 1000, "", "Waits before the rover skips the target."),
         [](auto& p) -> auto& { return p.mission.coordination.maxWaits; });
  addReal(t, realParam("keep_out_radius", 0, 100, "m", "A re-plan keeps out of this radius around where the other rover was at each earlier conflict."),
          [](auto& p) -> auto& { return p.mission.coordination.keepOutRadius; });
  addReal(t, realParam("dwell_check", 0, 3600, "s", "Each leg is also checked with the rover standing at its end this long."),
          [](auto& p) -> auto& { return p.mission.coordination.dwellCheck; });
  addReal(t, realParam("attitude_check", 0, 90, "deg", "A simulated try tilting past this is planned again, like a conflict (0 = off)."),
          [](auto& p) -> auto& { return p.mission.coordination.attitudeCheck; }, kDeg);
  addInt(t, intParam("max_pieces", 1, 100, "", "RRT* calls chained in one leg when a tree ends short of its goal."),
         [](auto& p) -> auto& { return p.mission.coordination.maxPieces; });
  // RRT* and eq. 9 (SPEC §3.2).
  addReal(t, realParam("range", 0.05, 100, "m", "RRT* range: the longest edge (paper 001: 1 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.range; });
  addInt(t, intParam("max_vertices", 2, 1000000, "", "RRT* grows each tree to this many vertices (paper 001: 1250)."),
         [](auto& p) -> auto& { return p.mission.coordination.rrt.maxVertices; });
  addReal(t, realParam("clearance", 0.01, 1000, "m", "Search bounds: the box of start and goal grown by this (paper 001: 2 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.clearance; });
  addReal(t, realParam("attitude_limit", 0.1, 90, "deg", "Roll/pitch limit of a valid edge and of the exceedance count (15°)."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.attitudeLimit; }, kDeg);
  addReal(t, realParam("exceedance_limit", 0.1, 90, "deg", "Samples with |roll| or |pitch| above this count as exceedances (paper 001: 15°)."),
          [](auto& p) -> auto& { return p.mission.exceedanceLimit; }, kDeg);
  addReal(t, realParam("goal_bias", 0, 1, "", "RRT* probability of sampling the goal."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.goalBias; });
  addInt(t, intParam("max_iterations", 1, 10000000, "", "Safety cap on RRT* iterations per tree."),
         [](auto& p) -> auto& { return p.mission.coordination.rrt.maxIterations; });
  addReal(t, realParam("w_r", 0, 1000, "", "Eq. 9 weight of the edge length (0.1)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wR; });
  addReal(t, realParam("w_phi", 0, 1000, "", "Eq. 9 weight of roll (0.4)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wPhi; });
  addReal(t, realParam("w_theta", 0, 1000, "", "Eq. 9 weight of pitch (0.4)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wTheta; });
  addReal(t, realParam("w_psi", 0, 1000, "", "Eq. 9 weight of the heading change (0.1)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wPsi; });
  addReal(t, realParam("n_r", 0.001, 1000, "m", "Eq. 9 normaliser of the edge length (1 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nR; });
  addReal(t, realParam("n_phi", 0.1, 180, "deg", "Eq. 9 normaliser of roll (15°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nPhi; }, kDeg);
  addReal(t, realParam("n_theta", 0.1, 180, "deg", "Eq. 9 normaliser of pitch (15°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nTheta; }, kDeg);
  addReal(t, realParam("n_psi", 0.1, 180, "deg", "Eq. 9 normaliser of the heading change (60°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nPsi; }, kDeg);
  // Rover simulation (SPEC §3.3).
  addReal(t, realParam("nominal_speed", 0.01, 0.5, "m/s", "Desired surge speed on flat ground (≈0.3 m/s)."),
          [](auto& p) -> auto& { return p.mission.coordination.controller.nominalSpeed; });
  addReal(t, realParam("lookahead", 0.05, 100, "m", "Line-of-sight guidance lookahead distance."),
          [](auto& p) -> auto& { return p.mission.coordination.controller.lookahead; });
  addReal(t, realParam("acceptance_radius", 0.01, 10, "m", "A waypoint counts as reached inside this radius."),
          [](auto& p) -> auto& { return p.mission.coordination.controller.acceptanceRadius; });
  addBool(t, boolParam("slip", "Simulate slip: a seeded lateral drift growing with slope (paper 001's cause of exceedances)."),
          [](auto& p) -> auto& { return p.mission.coordination.slip.enabled; });
  addReal(t, realParam("slip_gain", 0, 10, "", "Slip: lateral drift down the cross slope per unit sin(roll)."),
          [](auto& p) -> auto& { return p.mission.coordination.slip.gain; });
  addReal(t, realParam("slip_noise", 0, 10, "", "Slip: std of the random drift per unit sin(slope)."),
          [](auto& p) -> auto& { return p.mission.coordination.slip.noise; });
  // Hybrid (SPEC §4).
  addReal(t, realParam("hybrid_cell_m", 0.05, 1000, "m", "Hybrid: coverage grid cell inside each footprint (the sensing diameter)."),
          [](auto& p) -> auto& { return p.mission.hybridCell; });
  addReal(t, realParam("hybrid_coverage", 0.01, 1, "", "Hybrid: fraction of a footprint's free cells to cover."),
          [](auto& p) -> auto& { return p.mission.hybridCoverage; });
  addInverted(t, boolParam("hybrid_overlap", "Hybrid: all rovers cover the whole footprint (overlap) instead of one Voronoi region each."),
              [](auto& p) -> auto& { return p.mission.hybridVoronoi; });
  addInt(t, intParam("seed", 0, 9.0e18, "", "Seed of every RRT* tree, the slip noise and the coverage runs."),
         [](auto& p) -> auto& { return p.mission.seed; });
  addReal(t, realParam("pose_interval", 0.1, 600, "s", "Mission time between two pose events of the replay to a viewer."),
          [](auto& p) -> auto& { return p.poseInterval; });
  return t;
}

}  // namespace

const ParamTable<TeamPlannerParams>& teamParamTable() {
  static const ParamTable<TeamPlannerParams> table = buildTable();
  return table;
}

TeamPlannerParams parseTeamParams(const ParamSet& values) {
  TeamPlannerParams p = teamParamTable().parse(values);
  p.mission.validate();
  return p;
}

namespace {

std::vector<Eigen::Vector2d> decimate(const Trajectory& t, std::size_t every) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < t.samples.size(); i += every)
    out.emplace_back(t.samples[i].x, t.samples[i].y);
  if (!t.samples.empty() && (t.samples.size() - 1) % every != 0)
    out.emplace_back(t.samples.back().x, t.samples.back().y);
  return out;
}

Series curveSeries(std::string key, std::string xLabel, const std::vector<std::pair<double, double>>& c) {
  Series s{std::move(key), std::move(xLabel), "probability", {}, {}};
  for (const auto& [x, y] : c) {
    s.x.push_back(x);
    s.y.push_back(y);
  }
  return s;
}

}  // namespace

PlanResult toPlanResult(const TeamMissionResult& r, const TeamPlannerParams& p, bool hybrid,
                        double planWallSeconds) {
  PlanResult out;
  out.planner = hybrid ? "hybrid" : "team-search";
  out.cancelled = r.plan.cancelled;
  out.stopReason = r.plan.cancelled ? "cancelled" : "mission_complete";
  const TeamMetrics& m = r.metrics;
  out.metrics = {
      {"rovers", static_cast<double>(r.plan.trajectories.size()), "rovers"},
      {"mean_trajectory_m", m.meanTrajectoryM, "m"},
      {"mission_time_s", m.missionTimeS, "s"},
      {"mission_time_min", m.missionTimeS / 60.0, "min"},
      {"samples", static_cast<double>(m.samples), "samples"},
      {"exceedances", static_cast<double>(m.exceedances), "samples"},
      {"exceedance_fraction", m.exceedanceFraction, ""},
      {"max_roll_deg", m.maxRollDeg, "deg"},
      {"max_pitch_deg", m.maxPitchDeg, "deg"},
      {"collisions", static_cast<double>(m.collisions), "episodes"},
      {"min_separation_m", m.minSeparationM, "m"},
      {"accumulated_probability", m.accumulatedProbability, ""},
      {"single_rover_probability", m.singleRoverProbability, ""},
      {"route_score", m.routeScore, ""},
      {"targets", static_cast<double>(m.targets), "targets"},
      {"targets_reached", static_cast<double>(m.targetsReached), "legs"},
      {"targets_skipped", static_cast<double>(m.targetsSkipped), "legs"},
      {"targets_short", static_cast<double>(m.targetsShort), "legs"},
      {"targets_no_slot", static_cast<double>(m.targetsNoSlot), "legs"},
      {"unreachable_area_m2", r.reachability.unreachableAreaM2, "m2"},
      {"unreachable_search_cells", static_cast<double>(r.reachability.unreachableSearchCells), "cells"},
      {"unreachable_probability", r.reachability.unreachableMass, ""},
      {"replans", static_cast<double>(m.replans), "plans"},
      {"waits", static_cast<double>(m.waits), "waits"},
      {"rrt_calls", static_cast<double>(m.rrtCalls), "plans"},
      {"plan_wall_s", planWallSeconds, "s"},
  };
  out.warnings = missionWarnings(r);
  out.metrics.push_back({"warnings", static_cast<double>(out.warnings.size()), "warnings"});
  const double period = p.mission.coordination.controller.samplePeriod;
  const auto every = static_cast<std::size_t>(std::max(1L, std::lround(1.0 / period)));
  for (std::size_t k = 0; k < r.plan.trajectories.size(); ++k) {
    const Trajectory& t = r.plan.trajectories[k];
    const AttitudeExceedance e = attitudeExceedance(t, p.mission.exceedanceLimit);
    int reached = 0, skipped = 0, shortLegs = 0, replans = 0, waits = 0;
    for (const auto& leg : r.plan.legs) {
      if (leg.rover != static_cast<int>(k)) continue;
      replans += leg.replans;
      waits += leg.waits;
      if (leg.target < 0) continue;
      reached += leg.status == LegStatus::Reached;
      skipped += leg.status == LegStatus::Skipped;
      shortLegs += leg.status == LegStatus::Short;
    }
    Track track;
    track.rover = static_cast<int>(k);
    track.points = decimate(t, every);  // one point a second of the 10 Hz trajectory
    track.metrics = {{"trajectory_m", trajectoryLength(t), "m"},
                     {"time_s", t.samples.empty() ? 0.0 : t.samples.back().time, "s"},
                     {"samples", static_cast<double>(e.samples), "samples"},
                     {"exceedances", static_cast<double>(e.count), "samples"},
                     {"targets_reached", static_cast<double>(reached), "legs"},
                     {"targets_skipped", static_cast<double>(skipped), "legs"},
                     {"targets_short", static_cast<double>(shortLegs), "legs"},
                     {"replans", static_cast<double>(replans), "plans"},
                     {"waits", static_cast<double>(waits), "waits"}};
    out.tracks.push_back(std::move(track));
    out.overlays.push_back({"path", static_cast<int>(k), r.plan.paths[k]});
  }
  Polyline route{"route", -1, {r.route.startCentre}};
  route.points.insert(route.points.end(), r.route.centres.begin(), r.route.centres.end());
  out.overlays.insert(out.overlays.begin(), std::move(route));
  out.series.push_back(curveSeries("probability_vs_distance_team", "mean distance per rover (m)", r.curves.team));
  out.series.push_back(curveSeries("probability_vs_distance_single", "distance (m)", r.curves.single));
  out.series.push_back(curveSeries("probability_vs_distance_route", "route distance (m)", r.routeCurve));
  for (const Conflict& c : r.plan.conflicts) {
    char note[120];
    std::snprintf(note, sizeof note, "rovers %d and %d within %.2f m for %.1f s", c.other, c.rover,
                  c.distance, c.duration);
    out.incidents.push_back({"collision", c.rover, c.other, c.time, c.position, c.distance, note});
  }
  // Exceedance episodes: consecutive samples over the limit, reported once with the worst angle.
  const double limit = p.mission.exceedanceLimit;
  for (std::size_t k = 0; k < r.plan.trajectories.size(); ++k) {
    const auto& samples = r.plan.trajectories[k].samples;
    for (std::size_t i = 0; i < samples.size();) {
      auto over = [&](std::size_t j) {
        return std::max(std::abs(samples[j].roll), std::abs(samples[j].pitch));
      };
      if (over(i) <= limit) {
        ++i;
        continue;
      }
      std::size_t j = i;
      double worst = 0;
      for (; j < samples.size() && over(j) > limit; ++j) worst = std::max(worst, over(j));
      char note[120];
      std::snprintf(note, sizeof note, "|roll| or |pitch| up to %.2f° for %zu samples",
                    worst * 180.0 / std::numbers::pi, j - i);
      out.incidents.push_back({"exceedance", static_cast<int>(k), -1, samples[i].time,
                               {samples[i].x, samples[i].y}, worst * 180.0 / std::numbers::pi, note});
      i = j;
    }
  }
  for (const LegRecord& leg : r.plan.legs) {
    if (leg.status == LegStatus::Reached) continue;
    const Trajectory& t = r.plan.trajectories[leg.rover];
    const std::size_t i = std::min(t.samples.size() - 1,
                                   static_cast<std::size_t>(std::lround(leg.endTime / period)));
    out.incidents.push_back({legStatusName(leg.status), leg.rover, -1, leg.endTime,
                             {t.samples[i].x, t.samples[i].y}, static_cast<double>(leg.target),
                             "target " + std::to_string(leg.target) + ": " + leg.note});
  }
  for (const auto& [rover, target] : r.noSlot) {
    const Eigen::Vector2d at = r.route.centres[static_cast<std::size_t>(target)];
    out.incidents.push_back({"no_slot", rover, -1, 0.0, at, static_cast<double>(target),
                             "target " + std::to_string(target) +
                                 ": no valid ground for the rover's slot within half a footprint"});
  }
  return out;
}

namespace {

// Forwards a team mission to an event sink: the route and the search cells as soon as the route
// is chosen, each rover's planned path as it is accepted, progress per leg; then, once every
// rover is simulated, a replay of the team's poses in time order and the search cells they
// enter, at one event per pose interval of mission time.
class SinkObserver final : public TeamObserver {
 public:
  explicit SinkObserver(EventSink& sink) : sink_(sink) {}

  void routeChosen(const SearchGrid& grid, const Route& route) override {
    std::vector<Point2> pts{{route.startCentre.x(), route.startCentre.y()}};
    for (const auto& c : route.centres) pts.push_back({c.x(), c.y()});
    sink_.overlay("route", -1, pts);
    std::vector<CellUpdate> cells;
    for (int i = 0; i < grid.geometry().cellCount(); ++i)
      cells.push_back({i, static_cast<std::uint8_t>(grid.impassable.at(i) ? 2 : 1), 0});
    sink_.cellsChanged(cells);
  }
  void pieceAccepted(int rover, std::span<const Eigen::Vector2d> path,
                     std::span<const TrajectorySample> samples) override {
    (void)samples;
    std::vector<Point2> pts;
    for (std::size_t i = 1; i < path.size(); ++i) pts.push_back({path[i].x(), path[i].y()});
    if (!pts.empty()) sink_.overlay("path", rover, pts);
  }
  void legDone(const LegRecord& leg, int done, int total) override {
    (void)leg;
    Progress p;
    p.step = done;
    p.moves = done;
    p.fraction = total > 0 ? 0.9 * done / total : 0.9;
    sink_.progress(p);
  }

  void replay(const TeamMissionResult& r, double poseInterval, double period,
              const CancelToken* cancel) {
    const auto& traj = r.plan.trajectories;
    if (traj.empty()) return;
    std::size_t end = 0;
    for (const auto& t : traj) end = std::max(end, t.samples.size());
    const auto every = static_cast<std::size_t>(std::max(1L, std::lround(poseInterval / period)));
    const GridGeometry& g = r.grid.geometry();
    std::vector<std::uint32_t> visits(static_cast<std::size_t>(g.cellCount()), 0);
    std::vector<std::vector<std::uint8_t>> entered(traj.size(),
                                                   std::vector<std::uint8_t>(visits.size(), 0));
    int passable = 0, seen = 0;
    for (int i = 0; i < g.cellCount(); ++i) passable += r.grid.impassable.at(i) == 0;
    std::vector<RoverPose> poses(traj.size());
    std::vector<CellUpdate> changed;
    std::int64_t step = 0;
    for (std::size_t i = 0;; i = std::min(i + every, end - 1)) {
      if (cancel && cancel->cancelled()) return;
      changed.clear();
      for (std::size_t k = 0; k < traj.size(); ++k) {
        const auto& s = traj[k].samples[std::min(i, traj[k].samples.size() - 1)];
        poses[k] = {static_cast<int>(k), s.x, s.y, s.heading};
        const int col = static_cast<int>(std::floor(s.x / r.grid.footprint));
        const int row = g.rows - 1 - static_cast<int>(std::floor(s.y / r.grid.footprint));
        if (!g.contains(row, col)) continue;
        const int c = g.index(row, col);
        if (entered[k][c]) continue;
        entered[k][c] = 1;
        if (visits[c]++ == 0 && r.grid.impassable.at(c) == 0) ++seen;
        changed.push_back({c, 3, visits[c]});
      }
      if (!changed.empty()) sink_.cellsChanged(changed);
      sink_.roverPoses(step++, poses);
      Progress p;
      p.step = step;
      p.moves = static_cast<std::int64_t>(i);
      p.fraction = 0.9 + 0.1 * static_cast<double>(i + 1) / static_cast<double>(end);
      p.coverage = passable > 0 ? static_cast<double>(seen) / passable : 0.0;
      sink_.progress(p);
      if (i + 1 >= end) break;
    }
  }

 private:
  EventSink& sink_;
};

class TeamPlanner final : public Planner {
 public:
  explicit TeamPlanner(bool hybrid) : hybrid_(hybrid) {}
  std::string name() const override { return hybrid_ ? "hybrid" : "team-search"; }
  std::string summary() const override {
    return hybrid_ ? "Hybrid team mission (SPEC §4): the LHC_GW_CONV route picks the footprints, "
                     "the rovers cover each with the myopic DEM-aware planner; RRT* between "
                     "footprints, simulation and prioritised coordination as team-search."
                   : "Team search (Swinton et al.): LHC_GW_CONV team route over the PDM, RRT* "
                     "with the eq. 9 terrain cost per rover and segment, rover simulation at "
                     "10 Hz, prioritised multi-rover coordination.";
  }
  std::vector<ParamInfo> params() const override { return teamParamTable().infos(); }

  void validate(const PlanningProblem& problem, const ParamSet& params) const override {
    const TeamPlannerParams p = parseTeamParams(params);
    if (!problem.dem || problem.dem->geometry().cellCount() == 0)
      throw Error(ErrorCode::InvalidInput, "map", "the team planners need a DEM");
    const GridGeometry& g = problem.dem->geometry();
    if (problem.pdm && (problem.pdm->geometry.rows != g.rows || problem.pdm->geometry.cols != g.cols))
      throw Error(ErrorCode::InvalidInput, "pdm", "the PDM must have the DEM's rows and columns");
    if (problem.rovers.empty() || problem.rovers.size() > 64)
      throw Error(ErrorCode::InvalidInput, "rovers", "between 1 and 64 rovers are supported");
    if (p.mission.footprint < std::max(g.cellWidth, g.cellHeight))
      throwInvalidParameter("footprint_m", "must be at least the map cell size");
    const terrain::Traversability trav = terrain::traversability(*problem.dem, p.mission.traversability);
    planning::MissionGround ground;  // the one start check of every planner
    ground.dem = problem.dem.get();
    ground.classes = &trav.classes;
    ground.impassableDeg = p.mission.traversability.impassableDeg;
    planning::StartRules rules;
    rules.safetyDistance = p.mission.coordination.safetyDistance;
    planning::checkMissionStarts(ground, problem.rovers, rules);
  }

  GridGeometry eventGrid(const PlanningProblem& problem, const ParamSet& params) const override {
    if (!problem.dem) return {};
    const double f = parseTeamParams(params).mission.footprint;
    const GridGeometry& g = problem.dem->geometry();
    auto along = [f](double extent) { return std::max(1, static_cast<int>(std::ceil(extent / f - 1e-9))); };
    return {along(g.heightMetres()), along(g.widthMetres()), f, f};
  }

  PlanResult run(const PlanningProblem& problem, const ParamSet& params, EventSink* sink,
                 const CancelToken* cancel) const override {
    const auto t0 = std::chrono::steady_clock::now();
    const TeamPlannerParams p = parseTeamParams(params);
    if (!problem.dem) throw Error(ErrorCode::InvalidInput, "map", "the team planners need a DEM");
    std::vector<Pose> starts;
    for (const auto& s : problem.rovers) starts.push_back({s.position.x(), s.position.y(), s.heading});
    std::optional<SinkObserver> observer;
    if (sink) observer.emplace(*sink);
    const Raster<float> noPdm;
    TeamMissionParams mission = p.mission;
    mission.coordination.threads = problem.threads;
    // The simulated rover climbs against the map's body's gravity (issue 11: body-aware defaults);
    // the model's own default (Mars, paper 001's site) when the CRS names no known body.
    if (problem.body != terrain::Body::Unknown) mission.coordination.model.gravity = terrain::bodyGravity(problem.body);
    TeamMissionResult r = runTeamMission(*problem.dem, problem.pdm ? *problem.pdm : noPdm, starts,
                                         mission, hybrid_, observer ? &*observer : nullptr, cancel);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    PlanResult out = toPlanResult(r, p, hybrid_, wall);
    out.assumptions.push_back({"body", terrain::bodyName(problem.body)});
    out.assumptions.push_back({"gravity", problem.body != terrain::Body::Unknown ? "the map's body"
                                                                               : "default (Mars)"});
    if (sink && !out.cancelled) {
      sink->metrics(out.metrics);
      observer->replay(r, p.poseInterval, p.mission.coordination.controller.samplePeriod, cancel);
      if (cancel && cancel->cancelled()) {
        out.cancelled = true;
        out.stopReason = "cancelled";
      }
    }
    return out;
  }

 private:
  bool hybrid_;
};

}  // namespace

std::unique_ptr<Planner> makeTeamSearchPlanner() { return std::make_unique<TeamPlanner>(false); }
std::unique_ptr<Planner> makeHybridPlanner() { return std::make_unique<TeamPlanner>(true); }

}  // namespace rover::team
