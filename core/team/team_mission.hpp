#pragma once
// The team mission of paper 001 (SPEC §3) and the hybrid mission of SPEC §4, end to end, as the
// composition of its stages: reachability on the traversal lattice, the route generator
// (route_generator), the task builder (task_builder: formation slots at each target, plus the
// myopic coverage moves inside each footprint for the hybrid), the coordinator with a leg planner
// and the rover simulator (coordinator), and the metrics of SPEC §3.5 (team_metrics). Pure: the
// caller hands in the DEM and the PDM.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/team/coordination.hpp"
#include "core/team/formation.hpp"
#include "core/team/mission_params.hpp"
#include "core/team/route_generator.hpp"
#include "core/team/route_search.hpp"
#include "core/team/sub_teams.hpp"
#include "core/team/task_builder.hpp"
#include "core/team/team_metrics.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

// The ground the team cannot reach from its starts (TraversalLattice::reachable), known before
// the route is chosen: map cells with data off the team's reach, and search cells that are
// passable by their terrain classes but not by what the team can reach of them.
struct ReachabilityReport {
  std::int64_t unreachableMapCells = 0;
  double unreachableAreaM2 = 0;
  double unreachableMass = 0;        // PDM mass on those cells (of 1)
  int unreachableSearchCells = 0;
  double unreachableSearchMass = 0;  // original mass of those search cells
  // Excluded by the operator's keep-out zones (with their margin), not counted as unreachable:
  // map cells with data that were passable, and search cells that were possible targets.
  std::int64_t keepOutMapCells = 0;
  double keepOutAreaM2 = 0;
  double keepOutMass = 0;
  int keepOutSearchCells = 0;
  double keepOutSearchMass = 0;
};

// Everything a run produces.
struct TeamMissionResult {
  SearchGrid grid;  // Timed: unreachable ground counts as impassable; Paper: the terrain's own
  ReachabilityReport reachability;
  std::vector<std::pair<int, int>> noSlot;  // (rover, target) given no leg: no valid slot
  Route route;
  // The formation of the largest sub-team, square to the map (the orienteering route in timed mode
  // turns it at each target to the leg's heading: laneTurn, formation.hpp).
  std::vector<Eigen::Vector2d> slots;
  SubTeams subTeams;  // who visits which target (one team: every rover, every target)
  CoordinationResult plan;
  ProbabilityCurves curves;
  std::vector<std::pair<double, double>> routeCurve;  // accumulatedAlongRoute
  TeamMetrics metrics;
};

// What a user must be told before trusting the plan (empty: completed cleanly): short, skipped or
// slot-less legs, unreachable ground, collisions, attitude exceedances — one line each with the
// count. The server turns a non-empty list into "completed with warnings".
std::vector<std::string> missionWarnings(const TeamMissionResult& r);

// Told the route as soon as it is chosen, then everything coordination reports.
class TeamObserver : public CoordinationObserver {
 public:
  virtual void routeChosen(const SearchGrid& grid, const Route& route) {
    (void)grid;
    (void)route;
  }
};

// `pdm`: masses on the DEM's grid (empty: every cell with data equally likely). `hybrid` selects
// SPEC §4's mission. Throws rover::Error for bad parameters or inputs (field named).
TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<float>& pdm,
                                 const std::vector<Pose>& starts, const TeamMissionParams& params,
                                 bool hybrid, TeamObserver* observer = nullptr,
                                 const CancelToken* cancel = nullptr);

// The same on traversability classes the caller already holds (terrain::traversability of `dem`
// with params.traversability: a server computes them once per map, not once per mission).
TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                 const Raster<float>& pdm, const std::vector<Pose>& starts,
                                 const TeamMissionParams& params, bool hybrid,
                                 TeamObserver* observer = nullptr,
                                 const CancelToken* cancel = nullptr);

// The uniform PDM used when none is given: equal mass on every cell with data, summing to 1.
Raster<float> uniformPdm(const terrain::Dem& dem);

}  // namespace rover::team
