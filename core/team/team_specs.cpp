#include "core/team/team_specs.hpp"

#include "core/team/formation.hpp"
#include "core/team/team_entry.hpp"

namespace rover::team {

namespace {

PlannerSpecs makeSpecs(bool hybrid) {
  PlannerSpecs s;
  s.ground = Ground::DemAndPdm;
  s.starts = StartPlacement::Formation;
  s.progress = ProgressMeasure::Detection;
  s.progressSeries = "probability_vs_distance_team";
  s.secondsPerRun = true;
  s.metrics = {
      {"rovers", "rovers", "Rovers of the team."},
      {"mean_trajectory_m", "m", "Mean distance driven per rover."},
      {"mission_time_s", "s", "Time until the last rover ends."},
      {"mission_time_min", "min", "The same in minutes."},
      {"samples", "samples", "Simulated samples (10 Hz) of every rover."},
      {"exceedances", "samples", "Samples past the attitude limit."},
      {"exceedance_fraction", "", "Exceedances over samples."},
      {"max_roll_deg", "deg", "Largest roll of a sample."},
      {"max_pitch_deg", "deg", "Largest pitch of a sample."},
      {"collisions", "episodes", "Episodes of two rovers closer than the safety distance."},
      {"min_separation_m", "m", "Closest distance between two rovers."},
      {"accumulated_probability", "", "PDM mass sensed by the team."},
      {"single_rover_probability", "", "PDM mass one rover senses along the same distance."},
      {"route_score", "", "The team route's score over the PDM."},
      {"targets", "targets", "Targets of the route."},
      {"targets_reached", "legs", "Legs that reached their slot."},
      {"targets_skipped", "legs", "Legs given up."},
      {"targets_short", "legs", "Legs that ended away from their slot."},
      {"targets_no_slot", "legs", "Legs without a slot on valid ground."},
      {"unreachable_area_m2", "m2", "Ground no rover can reach."},
      {"unreachable_search_cells", "cells", "Search cells no rover can reach."},
      {"unreachable_probability", "", "PDM mass on ground no rover can reach."},
      {"keep_out_area_m2", "m2", "Ground closed by keep-out zones."},
      {"keep_out_search_cells", "cells", "Search cells closed by keep-out zones."},
      {"keep_out_probability", "", "PDM mass inside keep-out zones."},
      {"replans", "plans", "Paths planned again by the coordination."},
      {"waits", "waits", "Waits the coordination imposed."},
      {"rrt_calls", "plans", "RRT* searches."},
      {"plan_wall_s", "s", "Wall time of the planning (differs between runs of the same inputs)."},
      {"warnings", "warnings", "Warnings of the result."},
      {"energy_j", "J", "Driving energy of the team (paper 000 eq. 5)."},
      {"attitude_limit_deg", "deg", "The attitude limit the exceedances count against."},
  };
  // The composition of core/team/team_mission.hpp.
  s.stages = {
      {"reachability", "Reachability on the traversal lattice: ground no rover can reach is left out."},
      {"route", "The team route over the PDM's search cells (LHC_GW_CONV, LHC or lawnmower; SPEC §3)."},
      {"tasks", hybrid ? "Formation slots at each target, and the myopic coverage moves inside each "
                         "footprint (SPEC §4)."
                       : "Formation slots at each target."},
      {"coordination", "Each leg planned by RRT* with the eq. 9 terrain cost and simulated at 10 Hz; "
                       "prioritised coordination waits or replans to keep the rovers apart."},
      {"metrics", "The team's metrics and curves (SPEC §3.5)."},
  };
  return s;
}

}  // namespace

const PlannerSpecs& teamSpecs(bool hybrid) {
  static const PlannerSpecs team = makeSpecs(false), withCover = makeSpecs(true);
  return hybrid ? withCover : team;
}

std::vector<RoverStart> formationStarts(const terrain::Dem& dem, const ParamSet& params, int n) {
  const TeamPlannerParams typed = parseTeamParams(params);
  const GridGeometry& g = dem.geometry();
  const Eigen::Vector2d centre(g.widthMetres() / 2, g.heightMetres() / 2);
  std::vector<RoverStart> starts;
  for (const auto& p : formationStarts(dem, typed.mission, centre, n)) starts.push_back({{p.x, p.y}, p.heading});
  return starts;
}

}  // namespace rover::team
