#include "core/team/team_mission.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/team/traversal_lattice.hpp"

namespace rover::team {

const char* routeMethodName(RouteMethod m) {
  switch (m) {
    case RouteMethod::LhcGwConv:
      return "lhc_gw_conv";
    case RouteMethod::Lhc:
      return "lhc";
    case RouteMethod::Lawnmower:
      return "lawnmower";
  }
  return "unknown";
}

void TeamMissionParams::validate() const {
  validateRouteParams(route);
  coordination.validate();
  if (!std::isfinite(footprint) || !(footprint > 0) || footprint > 1e4)
    throwInvalidParameter("footprint_m", "must be a number of metres in (0, 10000]");
  if (!std::isfinite(sensingDiameter) || !(sensingDiameter > 0) || sensingDiameter > footprint)
    throwInvalidParameter("sensing_diameter_m", "must be > 0 and at most the footprint");
  const auto& t = traversability;
  if (!std::isfinite(t.highRiskDeg) || t.highRiskDeg <= 0 || t.highRiskDeg > 90)
    throwInvalidParameter("high_risk_deg", "must be in (0, 90]");
  if (!std::isfinite(t.impassableDeg) || t.impassableDeg < t.highRiskDeg || t.impassableDeg > 90)
    throwInvalidParameter("impassable_deg", "must be in [high_risk_deg, 90]");
  if (!std::isfinite(exceedanceLimit) || !(exceedanceLimit > 0) || exceedanceLimit > M_PI / 2)
    throwInvalidParameter("exceedance_limit", "must be in (0, 90] degrees");
  if (!std::isfinite(hybridCell) || !(hybridCell > 0) || hybridCell > footprint)
    throwInvalidParameter("hybrid_cell_m", "must be > 0 and at most the footprint");
  if (!std::isfinite(hybridCoverage) || !(hybridCoverage > 0) || hybridCoverage > 1)
    throwInvalidParameter("hybrid_coverage", "must be in (0, 1]");
}

std::vector<Eigen::Vector2d> formationSlots(int rovers, double footprint) {
  if (rovers < 1) return {};
  const int m = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(rovers)) - 1e-9));
  const double spacing = footprint / m;
  std::vector<Eigen::Vector2d> lattice;
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c)
      lattice.emplace_back((c - (m - 1) / 2.0) * spacing, ((m - 1) / 2.0 - r) * spacing);
  // Farthest-point order from the point nearest the centre; ties to the earlier lattice point.
  std::vector<Eigen::Vector2d> out;
  std::vector<bool> used(lattice.size(), false);
  std::size_t first = 0;
  for (std::size_t i = 1; i < lattice.size(); ++i)
    if (lattice[i].norm() < lattice[first].norm() - 1e-12) first = i;
  out.push_back(lattice[first]);
  used[first] = true;
  while (static_cast<int>(out.size()) < rovers) {
    std::size_t best = 0;
    double bestD = -1;
    for (std::size_t i = 0; i < lattice.size(); ++i) {
      if (used[i]) continue;
      double d = std::numeric_limits<double>::infinity();
      for (const auto& o : out) d = std::min(d, (lattice[i] - o).norm());
      if (d > bestD + 1e-12) {
        bestD = d;
        best = i;
      }
    }
    used[best] = true;
    out.push_back(lattice[best]);
  }
  return out;
}

CellIndex teamStartCell(const SearchGrid& grid, const std::vector<Pose>& starts) {
  Eigen::Vector2d c(0, 0);
  for (const auto& s : starts) c += Eigen::Vector2d(s.x, s.y);
  if (!starts.empty()) c /= static_cast<double>(starts.size());
  const int col = std::clamp(static_cast<int>(std::floor(c.x() / grid.footprint)), 0, grid.cols() - 1);
  const int fromBottom =
      std::clamp(static_cast<int>(std::floor(c.y() / grid.footprint)), 0, grid.rows() - 1);
  return {grid.rows() - 1 - fromBottom, col};
}

Route computeRoute(const SearchGrid& grid, CellIndex start, RouteMethod method,
                   const RouteParams& params) {
  switch (method) {
    case RouteMethod::Lawnmower:
      return lawnmower(grid, start, params.targets);
    case RouteMethod::Lhc: {
      RouteParams p = params;
      p.globalWarming = false;
      return lhcGwConv(grid, start, p);
    }
    case RouteMethod::LhcGwConv:
      break;
  }
  RouteParams p = params;
  p.globalWarming = true;
  return lhcGwConv(grid, start, p);
}

namespace {

TerrainEdgeModel wholeMapModel(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                               const TeamMissionParams& params) {
  const GridGeometry& g = dem.geometry();
  const RrtParams& rrt = params.coordination.rrt;
  const double res =
      rrt.edgeResolution > 0 ? rrt.edgeResolution : 0.25 * std::min(g.cellWidth, g.cellHeight);
  return TerrainEdgeModel(dem, classes, {{0, 0}, {g.widthMetres(), g.heightMetres()}},
                          rrt.attitudeLimit, res);
}

// The nearest point to `want` (rings of a quarter metre, up to `reach`) that RRT* accepts as a
// goal and that keeps the safety distance from `taken`.
std::optional<Eigen::Vector2d> nearestValid(const TerrainEdgeModel& model, Eigen::Vector2d want,
                                            double reach, double safety,
                                            const std::vector<Eigen::Vector2d>& taken,
                                            const Raster<std::uint8_t>* reachable = nullptr) {
  auto ok = [&](const Eigen::Vector2d& p) {
    if (!model.turnValid(p)) return false;
    if (reachable) {
      auto c = localToCell(reachable->geometry, p);
      if (!c || (*reachable)(c->row, c->col) == 0) return false;
    }
    for (const auto& t : taken)
      if ((t - p).norm() < safety) return false;
    return true;
  };
  if (ok(want)) return want;
  const double step = 0.25;
  for (double r = step; r <= reach + 1e-9; r += step) {
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * r / step)));
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      const Eigen::Vector2d p = want + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (ok(p)) return p;
    }
  }
  return std::nullopt;
}

// Per target, per rover: the slot goal (nullopt when there is none).
std::vector<std::vector<std::optional<Eigen::Vector2d>>> slotGoals(
    const terrain::Dem& dem, const Raster<std::uint8_t>& classes, int rovers, const Route& route,
    const TeamMissionParams& params, const Raster<std::uint8_t>* reachable) {
  const TerrainEdgeModel model = wholeMapModel(dem, classes, params);
  const auto slots = formationSlots(rovers, params.footprint);
  std::vector<std::vector<std::optional<Eigen::Vector2d>>> out;
  for (const auto& centre : route.centres) {
    std::vector<std::optional<Eigen::Vector2d>> goals;
    std::vector<Eigen::Vector2d> taken;
    for (int k = 0; k < rovers; ++k) {
      auto g = nearestValid(model, centre + slots[k], params.footprint / 2,
                            params.coordination.safetyDistance, taken, reachable);
      if (g) taken.push_back(*g);
      goals.push_back(g);
    }
    out.push_back(std::move(goals));
  }
  return out;
}

void requireStarts(const std::vector<Pose>& starts) {
  if (starts.empty() || starts.size() > 64)
    throw Error(ErrorCode::InvalidInput, "rovers", "between 1 and 64 rovers are supported");
}

}  // namespace

std::vector<RoverTask> teamSearchTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                       const std::vector<Pose>& starts, const Route& route,
                                       const TeamMissionParams& params,
                                       const Raster<std::uint8_t>* reachable) {
  requireStarts(starts);
  const int n = static_cast<int>(starts.size());
  const auto goals = slotGoals(dem, classes, n, route, params, reachable);
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
// centre lies in it are impassable or without data; heights are the mean of the rest.
coverage::World footprintWorld(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                               const Eigen::Vector2d& origin, int n, double cell) {
  const GridGeometry& g = dem.geometry();
  coverage::World w;
  w.obstacles = Raster<std::uint8_t>(GridGeometry{n, n, cell, cell}, 1);
  w.heights = Raster<double>(GridGeometry{n, n, cell, cell}, 0.0);
  std::vector<int> total(static_cast<std::size_t>(n * n), 0), blocked(total.size(), 0);
  std::vector<double> sum(total.size(), 0.0);
  const auto impassable = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
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
      if (classes(r, c) >= impassable) {
        ++blocked[i];
      } else {
        sum[i] += dem.z(r, c);
      }
    }
  }
  for (int i = 0; i < n * n; ++i) {
    if (total[i] == 0 || 2 * blocked[i] > total[i]) continue;
    w.obstacles.at(i) = 0;
    w.heights.at(i) = sum[i] / (total[i] - blocked[i]);
  }
  return w;
}

}  // namespace

std::vector<RoverTask> hybridTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   const std::vector<Pose>& starts, const Route& route,
                                   const TeamMissionParams& params, const CancelToken* cancel,
                                   const Raster<std::uint8_t>* reachable) {
  requireStarts(starts);
  const int n = static_cast<int>(starts.size());
  const auto goals = slotGoals(dem, classes, n, route, params, reachable);
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
      for (int c : cov.rovers[j].cells) leg.via.push_back(origin + cellToLocal(wg, wg.cell(c)));
      if (leg.via.size() < 2) continue;  // no moves: nothing to add
      leg.goal = leg.via.back();
      tasks[rovers[j]].legs.push_back(std::move(leg));
    }
  }
  return tasks;
}

std::vector<Pose> formationStarts(const terrain::Dem& dem, const TeamMissionParams& params,
                                  const Eigen::Vector2d& centre, int n) {
  params.validate();
  if (n < 1 || n > 64) throw Error(ErrorCode::InvalidInput, "rovers", "between 1 and 64 rovers are supported");
  const terrain::Traversability trav = terrain::traversability(dem, params.traversability);
  const TerrainEdgeModel model = wholeMapModel(dem, trav.classes, params);
  std::vector<Pose> out;
  std::vector<Eigen::Vector2d> taken;
  for (const auto& slot : formationSlots(n, params.footprint)) {
    auto p = nearestValid(model, centre + slot, params.footprint,
                          params.coordination.safetyDistance, taken);
    if (!p)
      throw Error(ErrorCode::InvalidInput, "rovers",
                  "no room for the rovers' formation near the start: give the starts explicitly");
    taken.push_back(*p);
    out.push_back({p->x(), p->y(), 0.0});
  }
  return out;
}

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

// Marks the map cells whose centre is within `radius` of p; adds the newly marked mass.
class DiscMarker {
 public:
  DiscMarker(const Raster<float>& pdm, double radius)
      : pdm_(pdm), seen_(static_cast<std::size_t>(pdm.geometry.cellCount()), 0), r_(radius) {}
  void mark(const Eigen::Vector2d& p) {
    const GridGeometry& g = pdm_.geometry;
    const double top = g.heightMetres();
    const int c0 = std::max(0, static_cast<int>(std::floor((p.x() - r_) / g.cellWidth)));
    const int c1 = std::min(g.cols - 1, static_cast<int>(std::floor((p.x() + r_) / g.cellWidth)));
    const int r0 = std::max(0, static_cast<int>(std::floor((top - p.y() - r_) / g.cellHeight)));
    const int r1 = std::min(g.rows - 1, static_cast<int>(std::floor((top - p.y() + r_) / g.cellHeight)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const int i = g.index(r, c);
        if (seen_[i] || (cellToLocal(g, {r, c}) - p).squaredNorm() > r_ * r_) continue;
        seen_[i] = 1;
        const float m = pdm_.at(i);
        if (std::isfinite(m)) mass_ += m;
      }
    }
  }
  double mass() const { return mass_; }

 private:
  const Raster<float>& pdm_;
  std::vector<std::uint8_t> seen_;
  double r_;
  double mass_ = 0;
};

}  // namespace

ProbabilityCurves accumulatedProbability(const Raster<float>& pdm,
                                         const std::vector<Trajectory>& trajectories,
                                         double sensingDiameter, std::size_t every) {
  ProbabilityCurves out;
  if (trajectories.empty() || pdm.empty()) return out;
  every = std::max<std::size_t>(every, 1);
  DiscMarker team(pdm, sensingDiameter / 2), single(pdm, sensingDiameter / 2);
  std::size_t end = 0;
  for (const auto& t : trajectories) end = std::max(end, t.samples.size());
  for (std::size_t i = 0; i < end; ++i) {
    double distance = 0;
    for (const auto& t : trajectories) {
      const auto& s = t.samples;
      if (s.empty()) continue;
      const TrajectorySample& x = s[std::min(i, s.size() - 1)];
      distance += x.distance;
      if (i < s.size()) team.mark({x.x, x.y});
    }
    if (i % every == 0 || i + 1 == end)
      out.team.emplace_back(distance / static_cast<double>(trajectories.size()), team.mass());
  }
  const auto& s0 = trajectories[0].samples;
  for (std::size_t i = 0; i < s0.size(); ++i) {
    single.mark({s0[i].x, s0[i].y});
    if (i % every == 0 || i + 1 == s0.size()) out.single.emplace_back(s0[i].distance, single.mass());
  }
  return out;
}

TeamMetrics teamMetrics(const CoordinationResult& plan, const ProbabilityCurves& curves,
                        const Route& route, double attitudeLimit, double safetyDistance) {
  TeamMetrics m;
  double sum = 0;
  for (const auto& t : plan.trajectories) {
    const double len = trajectoryLength(t);
    m.trajectoryM.push_back(len);
    sum += len;
    m.missionTimeS = std::max(m.missionTimeS, t.samples.empty() ? 0.0 : t.samples.back().time);
    const AttitudeExceedance e = attitudeExceedance(t, attitudeLimit);
    m.samples += e.samples;
    m.exceedances += e.count;
    for (const auto& s : t.samples) {
      m.maxRollDeg = std::max(m.maxRollDeg, std::abs(s.roll) * 180.0 / M_PI);
      m.maxPitchDeg = std::max(m.maxPitchDeg, std::abs(s.pitch) * 180.0 / M_PI);
    }
  }
  if (!plan.trajectories.empty()) m.meanTrajectoryM = sum / static_cast<double>(plan.trajectories.size());
  m.exceedanceFraction = m.samples ? static_cast<double>(m.exceedances) / static_cast<double>(m.samples) : 0.0;
  if (!plan.trajectories.empty()) {
    const SeparationReport sep = checkSeparation(plan.trajectories, safetyDistance);
    m.collisions = static_cast<int>(sep.conflicts.size());
    m.minSeparationM = std::isfinite(sep.minimumDistance) ? sep.minimumDistance : 0.0;
  }
  m.accumulatedProbability = curves.team.empty() ? 0.0 : curves.team.back().second;
  m.singleRoverProbability = curves.single.empty() ? 0.0 : curves.single.back().second;
  m.routeScore = route.score;
  m.targets = static_cast<int>(route.cells.size());
  for (const auto& leg : plan.legs) {
    if (leg.target < 0) continue;
    if (leg.status == LegStatus::Reached) ++m.targetsReached;
    if (leg.status == LegStatus::Skipped) ++m.targetsSkipped;
    if (leg.status == LegStatus::Short) ++m.targetsShort;
  }
  m.replans = plan.replans;
  m.waits = plan.waits;
  m.rrtCalls = plan.rrtCalls;
  return m;
}

TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<float>& pdmIn,
                                 const std::vector<Pose>& starts, const TeamMissionParams& params,
                                 bool hybrid, TeamObserver* observer, const CancelToken* cancel) {
  params.validate();
  requireStarts(starts);
  const GridGeometry& g = dem.geometry();
  if (g.cellCount() == 0) throw Error(ErrorCode::InvalidInput, "dem", "the DEM is empty");
  if (!pdmIn.empty() && (pdmIn.geometry.rows != g.rows || pdmIn.geometry.cols != g.cols))
    throw Error(ErrorCode::InvalidInput, "pdm", "the PDM must have the DEM's rows and columns");
  const Raster<float> pdm = pdmIn.empty() ? uniformPdm(dem) : pdmIn;
  // Traversability and the lattice once per mission, on the threads the caller granted.
  const terrain::Traversability trav = terrain::traversability(dem, params.traversability, false,
                                                               params.coordination.threads);
  const TraversalLattice lattice = makeLattice(dem, trav.classes, params.coordination);
  const bool timed = params.coordination.mode == CoordinationMode::Timed;

  TeamMissionResult out;
  // Reachability first: what the team can reach from its starts, before any target is chosen.
  std::vector<Eigen::Vector2d> startPoints;
  for (const auto& s : starts) startPoints.emplace_back(s.x, s.y);
  const Raster<std::uint8_t> reach = lattice.reachable(startPoints);
  Raster<std::uint8_t> reachClasses = trav.classes;
  const auto impassable = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  for (int i = 0; i < g.cellCount(); ++i) {
    if (reach.at(i) || trav.classes.at(i) >= impassable) continue;
    reachClasses.at(i) = impassable;
    if (std::isnan(dem.z.at(i))) continue;
    ++out.reachability.unreachableMapCells;
    if (std::isfinite(pdm.at(i))) out.reachability.unreachableMass += pdm.at(i);
  }
  out.reachability.unreachableAreaM2 =
      static_cast<double>(out.reachability.unreachableMapCells) * g.cellWidth * g.cellHeight;
  const SearchGrid terrainGrid = makeSearchGrid(pdm, trav.classes, params.footprint);
  SearchGrid reachGrid = makeSearchGrid(pdm, reachClasses, params.footprint);
  for (int i = 0; i < reachGrid.geometry().cellCount(); ++i)
    if (!terrainGrid.impassable.at(i) && reachGrid.impassable.at(i)) {
      ++out.reachability.unreachableSearchCells;
      out.reachability.unreachableSearchMass += terrainGrid.mass.at(i);
    }
  // Paper mode keeps today's route (on the terrain classes alone) so it can be compared.
  out.grid = timed ? std::move(reachGrid) : terrainGrid;
  out.route = computeRoute(out.grid, teamStartCell(out.grid, starts), params.routeMethod, params.route);
  out.routeCurve = accumulatedAlongRoute(out.grid, out.route);
  out.slots = formationSlots(static_cast<int>(starts.size()), params.footprint);
  if (observer) observer->routeChosen(out.grid, out.route);

  const Raster<std::uint8_t>* goalsOn = timed ? &reach : nullptr;
  const std::vector<RoverTask> tasks =
      hybrid ? hybridTasks(dem, trav.classes, starts, out.route, params, cancel, goalsOn)
             : teamSearchTasks(dem, trav.classes, starts, out.route, params, goalsOn);
  for (std::size_t k = 0; k < tasks.size(); ++k)
    for (int t = 0; t < static_cast<int>(out.route.cells.size()); ++t) {
      const auto& legs = tasks[k].legs;
      if (std::none_of(legs.begin(), legs.end(), [t](const Leg& l) { return l.target == t; }))
        out.noSlot.emplace_back(static_cast<int>(k), t);
    }
  TeamMissionParams p = params;
  p.coordination.slip.seed = deriveSeed(params.seed, 0x511b);
  out.plan = coordinate(dem, trav.classes, tasks, p.coordination, params.seed, observer, cancel,
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
