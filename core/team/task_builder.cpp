#include "core/team/task_builder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/common/error.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/planning/departure.hpp"
#include "core/team/formation.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::team {

void requireStarts(const std::vector<Pose>& starts) {
  planning::checkRoverCount(starts.size());
}


namespace {

// Per target, per rover: the slot goal (nullopt when there is none, or when the rover's sub-team
// does not visit the target). With sub-teams, a goal also keeps the goal spacing plus the
// departure margin (planning/departure.hpp) from the start of every rover planned after its own
// (the coordinator's departure order), so a rover stopped anywhere in its acceptance circle there
// can still leave past a team mate standing at its start. A team of 10 to 64 rovers stands over
// several search cells, its first targets lie among the starts, and a rover planned before a
// team mate still standing there (the inner rovers of a formation leave last,
// planning/departure.hpp) could never end a leg beside it (issue 25: 64 rovers on the default
// map, 4 of the 8 legs still lost were legs to the route's first target, among the starts, and
// with this rule the 64-rover mission lost 1 to 3 legs in all).
std::vector<std::vector<std::optional<Eigen::Vector2d>>> slotGoals(
    const terrain::Dem& dem, const Raster<std::uint8_t>& classes, const std::vector<Pose>& starts,
    const Route& route, const TeamMissionParams& params, const Raster<std::uint8_t>* reachable,
    const CancelToken* cancel, const SubTeams* teams) {
  const int rovers = static_cast<int>(starts.size());
  const TerrainEdgeModel model = wholeMapModel(dem, classes, params.coordination.rrt);
  const double spacing = goalSpacing(params.coordination);
  std::vector<int> everyone(static_cast<std::size_t>(rovers));
  for (int k = 0; k < rovers; ++k) everyone[static_cast<std::size_t>(k)] = k;
  // The formation of each sub-team size (at most two sizes: they differ by at most one).
  std::vector<std::vector<Eigen::Vector2d>> slotsOfSize(static_cast<std::size_t>(rovers) + 1);
  // Timed (ours): the goal's whole stop circle is ground to turn on; paper: the goal alone.
  const double stopCircle = params.coordination.mode == CoordinationMode::Timed
                                ? stopCircleRadius(params.coordination.controller)
                                : 0.0;
  // Each rover's place in the order the coordinator plans them (departureOrder over
  // departureOverGround, as there: in timed mode `reachable` is the lattice's flood from the starts); a
  // rover left boxed in (the coordinator refuses the start) last.
  std::vector<int> rank(static_cast<std::size_t>(rovers), rovers);
  if (teams) {
    std::vector<Eigen::Vector2d> at;
    for (const Pose& s : starts) at.emplace_back(s.x, s.y);
    const double safety = params.coordination.safetyDistance;
    const planning::Departure d = reachable ? departureOverGround(at, safety, *reachable).departure
                                            : planning::departureOrder(at, safety);
    for (std::size_t r = 0; r < d.order.size(); ++r) rank[static_cast<std::size_t>(d.order[r])] = static_cast<int>(r);
  }
  // ours (issue 25), the orienteering route in timed mode only: each target's slots turned to the
  // heading of the leg that reaches it (laneTurn, formation.hpp), so the rovers sweep distinct
  // lanes along it; LHC_GW_CONV, LHC, the lawnmower and the paper mode keep paper 001's square
  // slots. The heading rule is LaneHeading's, one per sub-team.
  const bool laneSlots = params.routeMethod == RouteMethod::Orienteering &&
                         params.coordination.mode == CoordinationMode::Timed;
  const int groups = teams ? teams->count() : 1;
  std::vector<LaneHeading> lanes;
  for (int g = 0; g < groups; ++g) {
    const std::vector<int>& members = teams ? teams->rovers[static_cast<std::size_t>(g)] : everyone;
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (int k : members) centroid += Eigen::Vector2d(starts[k].x, starts[k].y);
    if (!members.empty()) centroid /= static_cast<double>(members.size());
    lanes.emplace_back(centroid);
  }
  std::vector<std::vector<std::optional<Eigen::Vector2d>>> out;
  for (std::size_t t = 0; t < route.centres.size(); ++t) {
    // Cancelled: the targets left get no goals (64 rovers × 10 000 targets are 640 000 searches).
    if (cancel && cancel->cancelled()) break;
    const Eigen::Vector2d& centre = route.centres[t];
    const std::vector<int>& members =
        teams ? teams->rovers[static_cast<std::size_t>(teams->ofTarget[t])] : everyone;
    auto& slots = slotsOfSize[members.size()];
    if (slots.empty()) slots = goalSlots(static_cast<int>(members.size()), params.footprint, spacing);
    std::vector<Eigen::Vector2d> turned;
    if (laneSlots) turned = lanes[static_cast<std::size_t>(teams ? teams->ofTarget[t] : 0)].slotsAt(slots, centre);
    const std::vector<Eigen::Vector2d>& here = laneSlots ? turned : slots;
    std::vector<std::optional<Eigen::Vector2d>> goals(static_cast<std::size_t>(rovers));
    std::vector<Eigen::Vector2d> taken;
    for (std::size_t j = 0; j < members.size(); ++j) {
      const int me = members[j];
      const auto clearOfStarts = [&](const Eigen::Vector2d& p) {
        for (int k = 0; k < rovers; ++k)
          if (rank[static_cast<std::size_t>(k)] > rank[static_cast<std::size_t>(me)] &&
              (p - Eigen::Vector2d(starts[k].x, starts[k].y)).norm() < spacing + planning::kDepartureMargin)
            return false;
        return true;
      };
      const auto accept = teams ? std::function<bool(const Eigen::Vector2d&)>(clearOfStarts)
                                : std::function<bool(const Eigen::Vector2d&)>();
      auto g = nearestValid(model, centre + here[j], params.footprint / 2, spacing, taken,
                            reachable, stopCircle, accept);
      // A slot whose own half footprint holds no free ground (it lies in a wall beside the
      // target, and its team mates took the ground on this side) takes the free ground nearest
      // the target anywhere in the target's search cell — timed mode only, the paper mode keeps
      // its slots. On the Kepler site every no-slot was such a corner slot of a target on the
      // crater floor's edge, with ground for it 1 to 2 m from the target centre.
      if (!g && stopCircle > 0) {
        const auto inCell = [&](const Eigen::Vector2d& p) {
          return (p - centre).cwiseAbs().maxCoeff() <= params.footprint / 2 && (!accept || accept(p));
        };
        g = nearestValid(model, centre, params.footprint * M_SQRT1_2, spacing, taken, reachable,
                         stopCircle, inCell);
        // The cell has free ground, but all of it lies among the starts of rovers that leave
        // after this one (the cell overlaps the formation): the slot takes the free ground
        // nearest the target outside the formation, up to one and a half footprints from the
        // target centre (the cell's corners are 0.71 footprints out). On the Kepler site with 40
        // rovers, the target over the formation's top row left 3 of its 5 slots without ground
        // (issue 25); with this, all 5 have a slot, the farthest 5.3 m from the centre.
        if (!g && teams) {
          const auto inCellAnyStart = [&](const Eigen::Vector2d& p) {
            return (p - centre).cwiseAbs().maxCoeff() <= params.footprint / 2;
          };
          if (nearestValid(model, centre, params.footprint * M_SQRT1_2, spacing, taken, reachable,
                           stopCircle, inCellAnyStart))
            g = nearestValid(model, centre, 1.5 * params.footprint, spacing, taken, reachable, stopCircle, accept);
        }
      }
      if (g) taken.push_back(*g);
      goals[static_cast<std::size_t>(members[j])] = g;
    }
    out.push_back(std::move(goals));
  }
  return out;
}

}  // namespace

std::vector<RoverTask> teamSearchTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                       const std::vector<Pose>& starts, const Route& route,
                                       const TeamMissionParams& params,
                                       const Raster<std::uint8_t>* reachable,
                                       const CancelToken* cancel, const SubTeams* teams) {
  requireStarts(starts);
  const int n = static_cast<int>(starts.size());
  const auto goals = slotGoals(dem, classes, starts, route, params, reachable, cancel, teams);
  std::vector<RoverTask> tasks(starts.size());
  for (int k = 0; k < n; ++k) {
    tasks[k].start = starts[k];
    for (std::size_t t = 0; t < goals.size(); ++t)
      if (goals[t][k]) tasks[k].legs.push_back({*goals[t][k], {}, static_cast<int>(t)});
  }
  return tasks;
}

namespace {

// The coverage world of one footprint: cells of `cell` metres over the square centred on
// `centre`; a cell is an obstacle when it is off the map or more than half of the DEM cells whose
// centre lies in it are impassable or without data, or when one of them lies in a keep-out zone
// (core/planning/keep_out.hpp: any part of a zone blocks, not a majority); heights are the mean of
// the rest.
coverage::World footprintWorld(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                               const Eigen::Vector2d& origin, int n, double cell) {
  const GridGeometry& g = dem.geometry();
  coverage::World w;
  w.obstacles = Raster<std::uint8_t>(GridGeometry{n, n, cell, cell}, 1);
  w.heights = Raster<double>(GridGeometry{n, n, cell, cell}, 0.0);
  std::vector<int> total(static_cast<std::size_t>(n * n), 0), blocked(total.size(), 0);
  std::vector<std::uint8_t> zoned(total.size(), 0);
  std::vector<double> sum(total.size(), 0.0);
  const auto impassable = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  const auto keepOut = static_cast<std::uint8_t>(terrain::TerrainClass::KeepOut);
  const int c0 = std::max(0, static_cast<int>(std::floor(origin.x() / g.cellWidth)));
  const int c1 = std::min(g.cols - 1, static_cast<int>(std::ceil((origin.x() + n * cell) / g.cellWidth)));
  const double top = g.heightMetres();
  const int r0 = std::max(0, static_cast<int>(std::floor((top - origin.y() - n * cell) / g.cellHeight)));
  const int r1 = std::min(g.rows - 1, static_cast<int>(std::ceil((top - origin.y()) / g.cellHeight)));
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      const Eigen::Vector2d p = cellToLocal(g, {r, c}) - origin;
      const int fc = static_cast<int>(std::floor(p.x() / cell));
      const int fromBottom = static_cast<int>(std::floor(p.y() / cell));
      if (fc < 0 || fc >= n || fromBottom < 0 || fromBottom >= n) continue;
      const int i = (n - 1 - fromBottom) * n + fc;
      ++total[i];
      if (classes(r, c) == keepOut) zoned[i] = 1;
      if (classes(r, c) >= impassable) {
        ++blocked[i];
      } else {
        sum[i] += dem.z(r, c);
      }
    }
  }
  for (int i = 0; i < n * n; ++i) {
    if (total[i] == 0 || 2 * blocked[i] > total[i] || zoned[i]) continue;
    w.obstacles.at(i) = 0;
    w.heights.at(i) = sum[i] / (total[i] - blocked[i]);
  }
  return w;
}

}  // namespace

std::vector<RoverTask> hybridTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   const std::vector<Pose>& starts, const Route& route,
                                   const TeamMissionParams& params, const CancelToken* cancel,
                                   const Raster<std::uint8_t>* reachable, const SubTeams* teams) {
  requireStarts(starts);
  const int n = static_cast<int>(starts.size());
  const auto goals = slotGoals(dem, classes, starts, route, params, reachable, cancel, teams);
  const TerrainEdgeModel model = wholeMapModel(dem, classes, params.coordination.rrt);
  const int cells = std::max(1, static_cast<int>(std::lround(params.footprint / params.hybridCell)));
  const double cell = params.footprint / cells;
  coverage::CoverageParams cp;
  cp.mode = params.hybridVoronoi ? coverage::TeamMode::Voronoi : coverage::TeamMode::Overlap;
  cp.frontier = true;
  cp.coverage = params.hybridCoverage;
  cp.coverageCell = cell;
  std::vector<RoverTask> tasks(starts.size());
  for (int k = 0; k < n; ++k) tasks[k].start = starts[k];
  for (std::size_t t = 0; t < goals.size(); ++t) {
    if (cancel && cancel->cancelled()) break;
    const Eigen::Vector2d origin = route.centres[t] - Eigen::Vector2d::Constant(params.footprint / 2);
    coverage::World world = footprintWorld(dem, classes, origin, cells, cell);
    const GridGeometry& wg = world.geometry();
    // Coverage starts: the cell of each rover's slot goal (the nearest free one not taken).
    std::vector<coverage::StartCell> startCells;
    std::vector<int> rovers;  // rover of each coverage start
    std::vector<bool> taken(static_cast<std::size_t>(wg.cellCount()), false);
    for (int k = 0; k < n; ++k) {
      if (!goals[t][k]) continue;
      const Eigen::Vector2d p = *goals[t][k] - origin;
      int best = -1;
      double bestD = std::numeric_limits<double>::infinity();
      for (int i = 0; i < wg.cellCount(); ++i) {
        if (world.isObstacle(i) || taken[i]) continue;
        const double d = (cellToLocal(wg, wg.cell(i)) - p).norm();
        if (d < bestD) {
          bestD = d;
          best = i;
        }
      }
      tasks[k].legs.push_back({*goals[t][k], {}, static_cast<int>(t)});
      if (best < 0) continue;
      taken[best] = true;
      startCells.push_back({best, 0});
      rovers.push_back(k);
    }
    if (startCells.empty()) continue;
    cp.maxSteps = 0;
    coverage::CoverageResult cov = coverage::runCoverage(world, startCells, cp, nullptr, cancel);
    for (std::size_t j = 0; j < rovers.size(); ++j) {
      Leg leg;
      leg.goal = *goals[t][rovers[j]];
      // A coverage cell is free when most of its DEM cells are, so its centre may still be ground
      // a rover cannot stop on: each fixed point moves to the nearest stop within half a cell
      // (still sensing its own cell), or is left out. Before, such a last point made the whole
      // leg a skip ("invalid goal": 23 of 53 hybrid skips on the default map).
      for (int c : cov.rovers[j].cells)
        if (auto p = nearestValid(model, origin + cellToLocal(wg, wg.cell(c)), cell / 2, 0.0, {},
                                  reachable))
          leg.via.push_back(*p);
      // The rover drives through fixed points and stops at the last: timed (ours), that one's
      // stop circle must be ground to turn on, so trailing points that are not are left out.
      if (params.coordination.mode == CoordinationMode::Timed)
        while (leg.via.size() >= 2 &&
               !turnableAround(model, leg.via.back(), stopCircleRadius(params.coordination.controller)))
          leg.via.pop_back();
      if (leg.via.size() < 2) continue;  // no moves: nothing to add
      leg.goal = leg.via.back();
      tasks[rovers[j]].legs.push_back(std::move(leg));
    }
  }
  return tasks;
}

std::vector<RoverTask> SlotTasks::build(const std::vector<Pose>& starts, const Route& route,
                                        const CancelToken* cancel) const {
  return teamSearchTasks(dem_, classes_, starts, route, params_, reachable_, cancel, teams_);
}

std::vector<RoverTask> HybridTasks::build(const std::vector<Pose>& starts, const Route& route,
                                          const CancelToken* cancel) const {
  return hybridTasks(dem_, classes_, starts, route, params_, cancel, reachable_, teams_);
}

}  // namespace rover::team
