#include "core/team/team_mission.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/team/traversal_lattice.hpp"

namespace rover::team {

Raster<float> uniformPdm(const terrain::Dem& dem) {
  const GridGeometry& g = dem.geometry();
  Raster<float> out(g, 0.0f);
  out.geo = dem.z.geo;
  std::int64_t valid = 0;
  for (int i = 0; i < g.cellCount(); ++i) valid += std::isnan(dem.z.at(i)) ? 0 : 1;
  if (valid == 0) return out;
  const float m = static_cast<float>(1.0 / static_cast<double>(valid));
  for (int i = 0; i < g.cellCount(); ++i)
    if (!std::isnan(dem.z.at(i))) out.at(i) = m;
  return out;
}

namespace {
void requireGround(const terrain::Dem& dem, const Raster<float>& pdm) {
  const GridGeometry& g = dem.geometry();
  if (g.cellCount() == 0) throw Error(ErrorCode::InvalidInput, "dem", "the DEM is empty");
  if (!pdm.empty() && (pdm.geometry.rows != g.rows || pdm.geometry.cols != g.cols))
    throw Error(ErrorCode::InvalidInput, "pdm", "the PDM must have the DEM's rows and columns");
}
}  // namespace

TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<float>& pdm,
                                 const std::vector<Pose>& starts, const TeamMissionParams& params,
                                 bool hybrid, TeamObserver* observer, const CancelToken* cancel) {
  params.validate();
  requireStarts(starts);
  requireGround(dem, pdm);
  const terrain::Traversability trav = terrain::traversability(dem, params.traversability, false,
                                                               params.coordination.threads);
  return runTeamMission(dem, trav.classes, pdm, starts, params, hybrid, observer, cancel);
}

TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                 const Raster<float>& pdmIn, const std::vector<Pose>& starts,
                                 const TeamMissionParams& params, bool hybrid,
                                 TeamObserver* observer, const CancelToken* cancel) {
  params.validate();
  requireStarts(starts);
  requireGround(dem, pdmIn);
  const GridGeometry& g = dem.geometry();
  if (classes.geometry.rows != g.rows || classes.geometry.cols != g.cols)
    throw Error(ErrorCode::InvalidInput, "classes", "the classes must have the DEM's rows and columns");
  const Raster<float> pdm = pdmIn.empty() ? uniformPdm(dem) : pdmIn;
  // The keep-out zones laid on the classes (core/planning/keep_out.hpp): every stage below plans
  // on `zoned`, so the lattice, its flood, RRT*, the slots and the hybrid's grids all keep out.
  std::optional<Raster<std::uint8_t>> zonedOwn;
  if (!params.keepOut.empty()) {
    zonedOwn = classes;
    applyKeepOut(*zonedOwn, params.keepOut, params.keepOutMargin);
  }
  const Raster<std::uint8_t>& zoned = zonedOwn ? *zonedOwn : classes;
  // The lattice once per mission, on the threads the caller granted.
  const TraversalLattice lattice = makeLattice(dem, zoned, params.coordination);
  const bool timed = params.coordination.mode == CoordinationMode::Timed;

  TeamMissionResult out;
  // Reachability first: what the team can reach from its starts, before any target is chosen.
  std::vector<Eigen::Vector2d> startPoints;
  for (const auto& s : starts) startPoints.emplace_back(s.x, s.y);
  const Raster<std::uint8_t> reach = lattice.reachable(startPoints);
  Raster<std::uint8_t> reachClasses = zoned;
  const auto impassable = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  ReachabilityReport& u = out.reachability;
  for (int i = 0; i < g.cellCount(); ++i) {
    const bool data = !std::isnan(dem.z.at(i));
    const double mass = std::isfinite(pdm.at(i)) ? pdm.at(i) : 0.0;
    if (classes.at(i) < impassable && zoned.at(i) >= impassable && data) {
      ++u.keepOutMapCells;  // the operator's choice: excluded, not unreachable
      u.keepOutMass += mass;
    }
    if (reach.at(i) || zoned.at(i) >= impassable) continue;
    reachClasses.at(i) = impassable;
    if (!data) continue;
    ++u.unreachableMapCells;
    u.unreachableMass += mass;
  }
  const double cellArea = g.cellWidth * g.cellHeight;
  u.unreachableAreaM2 = static_cast<double>(u.unreachableMapCells) * cellArea;
  u.keepOutAreaM2 = static_cast<double>(u.keepOutMapCells) * cellArea;
  const SearchGrid terrainGrid = makeSearchGrid(pdm, classes, params.footprint);
  SearchGrid zonedGrid = makeSearchGrid(pdm, zoned, params.footprint);
  SearchGrid reachGrid = makeSearchGrid(pdm, reachClasses, params.footprint);
  // A search cell whose centre (the target itself) lies in a zone is never a target either.
  if (!params.keepOut.empty())
    for (int i = 0; i < zonedGrid.geometry().cellCount(); ++i)
      if (params.keepOut.zoneAt(zonedGrid.centre(zonedGrid.geometry().cell(i))) >= 0) {
        zonedGrid.impassable.at(i) = 1;
        reachGrid.impassable.at(i) = 1;
      }
  for (int i = 0; i < reachGrid.geometry().cellCount(); ++i) {
    if (terrainGrid.impassable.at(i)) continue;
    if (zonedGrid.impassable.at(i)) {
      ++u.keepOutSearchCells;
      u.keepOutSearchMass += terrainGrid.mass.at(i);
    } else if (reachGrid.impassable.at(i)) {
      ++u.unreachableSearchCells;
      u.unreachableSearchMass += terrainGrid.mass.at(i);
    }
  }
  // Paper mode keeps today's route (on the terrain classes and the zones alone) so it can be
  // compared.
  out.grid = timed ? std::move(reachGrid) : std::move(zonedGrid);
  const std::unique_ptr<RouteGenerator> routes = makeRouteGenerator(params.routeMethod, params.route);
  out.route = routes->generate(out.grid, teamStartCell(out.grid, starts));
  out.routeCurve = accumulatedAlongRoute(out.grid, out.route);
  // Sub-teams (issue 25, sub_teams.hpp): timed coordination only; the paper mode keeps paper 001's
  // single team of every rover at every target.
  out.subTeams = splitTeam(starts, out.route.centres, timed ? params.subTeamSize : 0);
  out.slots = goalSlots(static_cast<int>(out.subTeams.rovers.front().size()), params.footprint,
                        goalSpacing(params.coordination));
  if (observer) observer->routeChosen(out.grid, out.route);

  const Raster<std::uint8_t>* goalsOn = timed ? &reach : nullptr;
  const SubTeams* teams = out.subTeams.count() > 1 ? &out.subTeams : nullptr;
  std::unique_ptr<TaskBuilder> builder;
  if (hybrid) builder = std::make_unique<HybridTasks>(dem, zoned, params, goalsOn, teams);
  else builder = std::make_unique<SlotTasks>(dem, zoned, params, goalsOn, teams);
  const std::vector<RoverTask> tasks = builder->build(starts, out.route, cancel);
  // The (rover, target) pairs without a leg: one pass over each rover's legs (a search of its
  // legs per target was rovers × targets² — 6.4·10⁹ steps, tens of seconds nothing could cancel,
  // for 64 rovers and 10 000 targets).
  const int targetCount = static_cast<int>(out.route.cells.size());
  std::vector<std::uint8_t> served(static_cast<std::size_t>(targetCount));
  for (std::size_t k = 0; k < tasks.size() && !(cancel && cancel->cancelled()); ++k) {
    std::fill(served.begin(), served.end(), 0);
    for (const Leg& l : tasks[k].legs)
      if (l.target >= 0 && l.target < targetCount) served[static_cast<std::size_t>(l.target)] = 1;
    for (int t = 0; t < targetCount; ++t)
      if (!served[static_cast<std::size_t>(t)] &&
          out.subTeams.ofTarget[static_cast<std::size_t>(t)] == out.subTeams.ofRover[k])
        out.noSlot.emplace_back(static_cast<int>(k), t);
  }
  TeamMissionParams p = params;
  p.coordination.slip.seed = deriveSeed(params.seed, 0x511b);
  out.plan = coordinate(dem, zoned, tasks, p.coordination, params.seed, observer, cancel,
                        &lattice);
  if (cancel && cancel->cancelled()) out.plan.cancelled = true;
  out.curves = accumulatedProbability(pdm, out.plan.trajectories, params.sensingDiameter);
  out.metrics = teamMetrics(out.plan, out.curves, out.route, params.exceedanceLimit,
                            params.coordination.safetyDistance);
  out.metrics.targetsNoSlot = static_cast<int>(out.noSlot.size());
  return out;
}

std::vector<std::string> missionWarnings(const TeamMissionResult& r) {
  std::vector<std::string> out;
  const TeamMetrics& m = r.metrics;
  char buf[200];
  auto add = [&](long long n, const char* what) {
    if (n <= 0) return;
    std::snprintf(buf, sizeof buf, "%lld %s", n, what);
    out.emplace_back(buf);
  };
  add(m.targetsShort, "legs ended short of their target");
  add(m.targetsSkipped, "legs skipped");
  add(m.targetsNoSlot, "rover slots at a target without valid ground (no leg)");
  add(m.collisions, "collisions left in the plan");
  add(static_cast<long long>(m.exceedances), "samples past the roll/pitch limit");
  const ReachabilityReport& u = r.reachability;
  if (u.unreachableMapCells > 0) {
    std::snprintf(buf, sizeof buf,
                  "%.0f m² of the map (%d search cells, probability %.4f) cannot be reached from "
                  "the start",
                  u.unreachableAreaM2, u.unreachableSearchCells, u.unreachableMass);
    out.emplace_back(buf);
  }
  if (r.plan.cancelled) out.emplace_back("cancelled before the end");
  return out;
}

}  // namespace rover::team
