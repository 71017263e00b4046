// A team mission's result in the planner-neutral form: metrics, tracks, overlays, curves and
// one incident per collision, exceedance episode, leg that did not reach and slot-less target.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/team/motion_series.hpp"
#include "core/team/team_entry.hpp"
#include "core/team/team_incidents.hpp"

namespace rover::team {

namespace {

std::vector<Eigen::Vector2d> decimate(const Trajectory& t, std::size_t every) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < t.samples.size(); i += every)
    out.emplace_back(t.samples[i].x, t.samples[i].y);
  if (!t.samples.empty() && (t.samples.size() - 1) % every != 0)
    out.emplace_back(t.samples.back().x, t.samples.back().y);
  return out;
}

// Pitch and roll against mission time, one point a second of the 10 Hz trajectory: the sample of
// largest magnitude in each second, so no excursion over the attitude limit is averaged away.
void attitudeSeries(const Trajectory& t, std::size_t every, int rover, std::vector<Series>& out) {
  Series pitch{"pitch_deg_rover_" + std::to_string(rover), "time (s)", "pitch_deg", {}, {}};
  Series roll{"roll_deg_rover_" + std::to_string(rover), "time (s)", "roll_deg", {}, {}};
  const double deg = 180.0 / std::numbers::pi;
  for (std::size_t i = 0; i < t.samples.size(); i += every) {
    const std::size_t end = std::min(t.samples.size(), i + every);
    std::size_t p = i, q = i;
    for (std::size_t j = i; j < end; ++j) {
      if (std::abs(t.samples[j].pitch) > std::abs(t.samples[p].pitch)) p = j;
      if (std::abs(t.samples[j].roll) > std::abs(t.samples[q].roll)) q = j;
    }
    pitch.x.push_back(t.samples[i].time);
    pitch.y.push_back(t.samples[p].pitch * deg);
    roll.x.push_back(t.samples[i].time);
    roll.y.push_back(t.samples[q].roll * deg);
  }
  out.push_back(std::move(pitch));
  out.push_back(std::move(roll));
}

Series curveSeries(std::string key, std::string xLabel, const std::vector<std::pair<double, double>>& c) {
  Series s{std::move(key), std::move(xLabel), "probability", {}, {}};
  for (const auto& [x, y] : c) {
    s.x.push_back(x);
    s.y.push_back(y);
  }
  return s;
}

// Each route target with the fate of its legs (PlanResult::targets), in visiting order.
std::vector<RouteTarget> routeTargets(const TeamMissionResult& r) {
  std::vector<RouteTarget> out;
  for (std::size_t i = 0; i < r.route.centres.size(); ++i)
    out.push_back({static_cast<int>(i), r.route.centres[i], TargetStatus::Skipped, 0, 0, 0, 0});
  for (const LegRecord& leg : r.plan.legs) {
    if (leg.target < 0 || leg.target >= static_cast<int>(out.size())) continue;
    RouteTarget& t = out[static_cast<std::size_t>(leg.target)];
    t.reached += leg.status == LegStatus::Reached;
    t.shortLegs += leg.status == LegStatus::Short;
    t.skipped += leg.status == LegStatus::Skipped;
  }
  for (const auto& [rover, target] : r.noSlot)
    if (target >= 0 && target < static_cast<int>(out.size())) ++out[static_cast<std::size_t>(target)].noSlot;
  for (RouteTarget& t : out) {
    const int legs = t.reached + t.shortLegs + t.skipped + t.noSlot;
    t.status = legs == 0                      ? TargetStatus::Skipped
               : t.reached == legs            ? TargetStatus::Reached
               : t.noSlot == legs             ? TargetStatus::Unreachable
               : t.skipped + t.noSlot == legs ? TargetStatus::Skipped
                                              : TargetStatus::Short;
  }
  return out;
}

}  // namespace

PlanResult toPlanResult(const TeamMissionResult& r, const TeamPlannerParams& p, bool hybrid,
                        double planWallSeconds) {
  PlanResult out;
  out.planner = hybrid ? "hybrid" : "team-search";
  out.cancelled = r.plan.cancelled;
  out.stopReason = r.plan.cancelled ? StopReason::Cancelled : StopReason::MissionComplete;
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
      {"keep_out_area_m2", r.reachability.keepOutAreaM2, "m2"},
      {"keep_out_search_cells", static_cast<double>(r.reachability.keepOutSearchCells), "cells"},
      {"keep_out_probability", r.reachability.keepOutMass, ""},
      {"replans", static_cast<double>(m.replans), "plans"},
      {"waits", static_cast<double>(m.waits), "waits"},
      {"rrt_calls", static_cast<double>(m.rrtCalls), "plans"},
      {"plan_wall_s", planWallSeconds, "s"},
  };
  if (r.subTeams.count() > 1)
    out.metrics.push_back({"sub_teams", static_cast<double>(r.subTeams.count()), "teams"});
  std::vector<double> distances, energies;
  for (const Trajectory& t : r.plan.trajectories) {
    distances.push_back(trajectoryLength(t));
    energies.push_back(driveEnergyJ(t, p.mission.coordination.model));
  }
  out.warnings = missionWarnings(r);
  for (auto& w : planning::rangeWarnings(p.range, distances, energies)) out.warnings.push_back(std::move(w));
  out.metrics.push_back({"warnings", static_cast<double>(out.warnings.size()), "warnings"});
  const double period = p.mission.coordination.controller.samplePeriod;
  const auto every = static_cast<std::size_t>(std::max(1L, std::lround(1.0 / period)));
  double energy = 0;
  for (std::size_t k = 0; k < r.plan.trajectories.size(); ++k) {
    const Trajectory& t = r.plan.trajectories[k];
    const double roverEnergy = energies[k];
    energy += roverEnergy;
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
    track.samples.reserve(t.samples.size());  // the exports' CSV: every 10 Hz sample
    for (const TrajectorySample& s : t.samples)
      track.samples.push_back({s.time, {s.x, s.y}, s.heading, s.roll, s.pitch, s.speed, s.z});
    track.metrics = {{"trajectory_m", distances[k], "m"},
                     {"time_s", t.samples.empty() ? 0.0 : t.samples.back().time, "s"},
                     {"energy_j", roverEnergy, "J"},
                     {"samples", static_cast<double>(e.samples), "samples"},
                     {"exceedances", static_cast<double>(e.count), "samples"},
                     {"targets_reached", static_cast<double>(reached), "legs"},
                     {"targets_skipped", static_cast<double>(skipped), "legs"},
                     {"targets_short", static_cast<double>(shortLegs), "legs"},
                     {"replans", static_cast<double>(replans), "plans"},
                     {"waits", static_cast<double>(waits), "waits"}};
    // Which sub-team the rover flies in (sub_teams.hpp), only when the team was split: a one-team
    // result stays as it was.
    if (r.subTeams.count() > 1)
      track.metrics.push_back({"sub_team", static_cast<double>(r.subTeams.ofRover[k]), ""});
    out.tracks.push_back(std::move(track));
    out.overlays.push_back({"path", static_cast<int>(k), r.plan.paths[k]});
    attitudeSeries(t, every, static_cast<int>(k), out.series);
    motionSeries(t, every, static_cast<int>(k), p.mission.coordination.model, out.series);
  }
  Polyline route{"route", -1, {r.route.startCentre}};
  route.points.insert(route.points.end(), r.route.centres.begin(), r.route.centres.end());
  out.overlays.insert(out.overlays.begin(), std::move(route));
  out.metrics.push_back({"energy_j", energy, "J"});  // motion_series.hpp: paper 000 eq. 5
  out.targets = routeTargets(r);
  out.metrics.push_back({"attitude_limit_deg", p.mission.exceedanceLimit * 180.0 / std::numbers::pi, "deg"});
  out.series.push_back(curveSeries("probability_vs_distance_team", "mean distance per rover (m)", r.curves.team));
  out.series.push_back(curveSeries("probability_vs_distance_single", "distance (m)", r.curves.single));
  out.series.push_back(curveSeries("probability_vs_distance_route", "route distance (m)", r.routeCurve));
  for (const Conflict& c : r.plan.conflicts)
    out.incidents.push_back(collisionIncident(c, p.mission.coordination.safetyDistance));
  // Exceedance episodes: consecutive samples over the limit, reported once with the worst angle.
  for (std::size_t k = 0; k < r.plan.trajectories.size(); ++k) {
    ExceedanceScan scan(static_cast<int>(k), p.mission.exceedanceLimit);
    for (const TrajectorySample& s : r.plan.trajectories[k].samples)
      if (auto i = scan.add(s)) out.incidents.push_back(std::move(*i));
    if (auto i = scan.finish()) out.incidents.push_back(std::move(*i));
  }
  for (const LegRecord& leg : r.plan.legs) {
    if (leg.status == LegStatus::Reached) continue;
    const Trajectory& t = r.plan.trajectories[leg.rover];
    const std::size_t i = std::min(t.samples.size() - 1,
                                   static_cast<std::size_t>(std::lround(leg.endTime / period)));
    out.incidents.push_back(legIncident(leg, {t.samples[i].x, t.samples[i].y}));
  }
  for (const auto& [rover, target] : r.noSlot)
    out.incidents.push_back(noSlotIncident(rover, target, r.route.centres[static_cast<std::size_t>(target)],
                                           p.mission.footprint,
                                           p.mission.coordination.mode == CoordinationMode::Timed));
  return out;
}

}  // namespace rover::team
