// Keep-out zones (issue 13): the one rasterisation (core/grid/geometry), and every planner
// respecting it (core/planning/keep_out.hpp) on literal grids.
#include <doctest/doctest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/grid/geometry.hpp"
#include "core/planning/keep_out.hpp"
#include "core/team/team_entry.hpp"
#include "core/team/team_mission.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"
#include "grid_literals.hpp"

using namespace rover;

namespace {

Polygon box(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
}

// The marked cells drawn as the grid is: row 0 (north) first, '#' marked.
std::vector<std::string> picture(const GridGeometry& g, const std::vector<std::uint8_t>& cells) {
  std::vector<std::string> out(g.rows, std::string(g.cols, '.'));
  for (int i = 0; i < g.cellCount(); ++i)
    if (cells[i]) out[g.cell(i).row][g.cell(i).col] = '#';
  return out;
}

}  // namespace

TEST_CASE("keep-out: point in polygon, holes by the even-odd rule") {
  Polygon p = box(0, 0, 4, 4);
  CHECK(insidePolygon(p, {1, 1}));
  CHECK_FALSE(insidePolygon(p, {5, 1}));
  CHECK_FALSE(insidePolygon(p, {-0.1, 2}));
  p.push_back({{1, 1}, {3, 1}, {3, 3}, {1, 3}});  // a hole
  CHECK_FALSE(insidePolygon(p, {2, 2}));
  CHECK(insidePolygon(p, {0.5, 2}));
  const Polygon tri{{{0, 0}, {4, 0}, {0, 4}}};
  CHECK(insidePolygon(tri, {1, 1}));
  CHECK_FALSE(insidePolygon(tri, {3, 3}));
}

TEST_CASE("keep-out: a cell is marked when the polygon overlaps it with positive area") {
  const GridGeometry g{4, 6, 1.0, 1.0};  // 6 × 4 m
  // Exactly on cell borders: x 1..3, y 1..2 marks the two cells inside, not their neighbours.
  CHECK(picture(g, polygonCells(g, {box(1, 1, 3, 2)})) ==
        std::vector<std::string>{"......", "......", ".##...", "......"});
  // Off the borders: x 1.5..3.2, y 0.5..1.2 overlaps cols 1..3 of the two bottom rows.
  CHECK(picture(g, polygonCells(g, {box(1.5, 0.5, 3.2, 1.2)})) ==
        std::vector<std::string>{"......", "......", ".###..", ".###.."});
  // A thin diagonal sliver marks every cell it crosses, though it holds no cell centre.
  const Polygon sliver{{{0.1, 0.1}, {5.9, 3.9}, {5.8, 3.9}}};
  const auto s = picture(g, polygonCells(g, {sliver}));
  CHECK(s[3][0] == '#');
  CHECK(s[0][5] == '#');
  CHECK(s[0][0] == '.');
  // The margin: grown by 0.5 m the border-aligned box takes its 8-neighbours too.
  CHECK(picture(g, polygonCells(g, {box(1, 1, 3, 2)}, 0.5)) ==
        std::vector<std::string>{"......", "####..", "####..", "####.."});
  // A zone partly off the grid marks what lies on it.
  CHECK(picture(g, polygonCells(g, {box(4.5, -3, 9, 0.5)})) ==
        std::vector<std::string>{"......", "......", "......", "....##"});
  // Holes are not marked when no hole edge crosses the cell.
  Polygon ring = box(0, 0, 6, 4);
  ring.push_back(box(1, 1, 5, 3)[0]);
  CHECK(picture(g, polygonCells(g, {ring})) ==
        std::vector<std::string>{"######", "#....#", "#....#", "######"});
}

TEST_CASE("keep-out: a zone across a corridor makes coverage go round it") {
  // A 12 × 5 m corridor; the zone is a wall across it at x 5..7 from the south edge up to y 4,
  // leaving the northern lane open. The rover starts west of it.
  coverage::World world = test::worldFrom({
      "............",
      "............",
      "............",
      "............",
      "............",
  });
  PlanningProblem problem;
  problem.world = world;
  problem.rovers = {{{0.5, 0.5}, 0.0}};
  problem.keepOut.zones = {box(5, -1, 7, 4)};
  const auto planner = coverage::makeCoveragePlanner();
  ParamSet params{{"frontier", true}, {"coverage", 1.0}};
  planner->validate(problem, params);
  const PlanResult r = planner->run(problem, params, nullptr, nullptr);
  const Track& t = r.tracks.at(0);
  bool east = false;
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    CHECK(problem.keepOut.zoneAt(t.points[i]) < 0);
    CHECK_FALSE((t.points[i].x() > 5 && t.points[i].x() < 7 && t.points[i].y() < 4));
    east = east || t.points[i].x() > 7;
    // No move between two cells crosses the zone: both ends are free and adjacent.
    if (i > 0) CHECK((t.points[i] - t.points[i - 1]).norm() < 1.5);
  }
  CHECK(east);  // round the zone through the northern lane
  auto metric = [&](const std::string& k) {
    return std::find_if(r.metrics.begin(), r.metrics.end(), [&](const Metric& m) { return m.key == k; })->value;
  };
  CHECK(metric("keep_out_cells") == 8);
  CHECK(metric("coverage") == doctest::Approx(1.0));
  CHECK(metric("unreachable_cells") == 0);

  // A start inside the zone is refused, naming the rover.
  problem.rovers = {{{6, 1}, 0.0}};
  CHECK_THROWS_WITH_AS(planner->validate(problem, params),
                       "rovers[0]: start is inside keep-out zone 0", Error);
}

namespace {

// 20 × 12 m of flat ground with two rovers west of a zone.
team::TeamMissionResult wallMission(const terrain::Dem& dem, const KeepOut& zones, int targets,
                                    const Raster<float>& pdm, bool hybrid = false,
                                    team::CoordinationMode mode = team::CoordinationMode::Timed) {
  team::TeamMissionParams p;
  p.coordination.mode = mode;
  p.route.targets = targets;
  p.coordination.threads = 2;
  p.keepOut = zones;
  const std::vector<team::Pose> starts{{3, 6, 0}, {3, 8, 0}};
  return team::runTeamMission(dem, pdm, starts, p, hybrid);
}

}  // namespace

TEST_CASE("keep-out: no team sample enters a zone, and a target in a zone is never chosen") {
  const terrain::Dem dem = test::demFrom(48, 80, 0.25, [](double, double) { return 0.0; });
  const GridGeometry& g = dem.geometry();
  KeepOut zones;
  // A wall x 7.1..12.9 from y 3 past the north edge: the gap is the southern 3 m. Most of the
  // probability lies under it, the rest mostly east of it; the search cells x 5..15, y 5..12 are
  // mostly in the zone (and the centre (7.5, 7.5) is in it), so never targets.
  zones.zones = {box(7.1, 3, 12.9, 13)};
  Raster<float> pdm(g, 0.0f);
  double sum = 0;
  for (int i = 0; i < g.cellCount(); ++i) {
    const Eigen::Vector2d p = cellToLocal(g, g.cell(i));
    const double w = zones.zoneAt(p) >= 0 ? 50.0 : p.x() > 13 ? 5.0 : 1.0;
    pdm.at(i) = static_cast<float>(w);
    sum += w;
  }
  for (int i = 0; i < g.cellCount(); ++i) pdm.at(i) = static_cast<float>(pdm.at(i) / sum);

  const team::TeamMissionResult r = wallMission(dem, zones, 4, pdm);
  int samples = 0;
  bool east = false;
  for (const auto& t : r.plan.trajectories)
    for (const auto& s : t.samples) {
      ++samples;
      CHECK(zones.zoneAt({s.x, s.y}) < 0);
      // Not even on a map cell the zone touches.
      const CellIndex c = *localToCell(g, {s.x, s.y});
      CHECK(zones.zoneOverlapping(g, c) < 0);
      east = east || s.x > 13;
    }
  CHECK(samples > 100);
  CHECK(east);  // round the wall, through the southern gap
  for (const auto& path : r.plan.paths)
    for (const auto& p : path) CHECK(zones.zoneAt(p) < 0);
  // No target's centre is in the zone; the zone's search cells are counted as excluded, not as
  // unreachable.
  for (const auto& c : r.route.centres) CHECK(zones.zoneAt(c) < 0);
  CHECK(r.reachability.keepOutSearchCells >= 1);
  CHECK(r.reachability.unreachableSearchCells == 0);
  CHECK(r.reachability.unreachableMapCells == 0);
  CHECK(r.reachability.keepOutAreaM2 >= 5.8 * 9);
  CHECK(r.reachability.keepOutMass > 0.3);
  CHECK(r.metrics.collisions == 0);

  // The same through the planner registry: the problem's zones reach the team planner, and a
  // start on a zone's cell is refused.
  const auto planner = team::makeTeamSearchPlanner();
  PlanningProblem problem;
  problem.dem = std::make_shared<terrain::Dem>(dem);
  problem.rovers = {{{10, 6}, 0.0}};  // inside
  problem.keepOut = zones;
  CHECK_THROWS_WITH_AS(planner->validate(problem, {}), "rovers[0]: start is inside keep-out zone 0", Error);
  problem.rovers = {{{7.0, 6}, 0.0}};  // outside, but on the 0.25 m cell x 7..7.25
  CHECK_THROWS_WITH_AS(planner->validate(problem, {}),
                       "rovers[0]: start is on a map cell keep-out zone 0 overlaps (a rover never stands on one)",
                       Error);
}

TEST_CASE("keep-out: the hybrid mission and paper coordination keep out too") {
  const terrain::Dem dem = test::demFrom(48, 80, 0.25, [](double, double) { return 0.0; });
  KeepOut zones;
  zones.zones = {box(7.1, 3, 12.9, 13)};
  for (const bool hybrid : {false, true}) {
    const auto mode = hybrid ? team::CoordinationMode::Timed : team::CoordinationMode::Paper;
    const team::TeamMissionResult r = wallMission(dem, zones, 3, Raster<float>{}, hybrid, mode);
    int samples = 0;
    for (const auto& t : r.plan.trajectories)
      for (const auto& s : t.samples) {
        ++samples;
        CHECK(zones.zoneOverlapping(dem.geometry(), *localToCell(dem.geometry(), {s.x, s.y})) < 0);
      }
    MESSAGE(std::string(hybrid ? "hybrid" : "paper") << ": " << samples << " samples, legs reached "
                                          << r.metrics.targetsReached << ", short " << r.metrics.targetsShort);
    CHECK(samples > 50);
    for (const auto& c : r.route.centres) CHECK(zones.zoneAt(c) < 0);
  }
}

TEST_CASE("keep-out: the classes mark the zone KeepOut and its margin Impassable") {
  Raster<std::uint8_t> classes(GridGeometry{4, 6, 1.0, 1.0}, 0);
  classes(0, 5) = static_cast<std::uint8_t>(terrain::TerrainClass::NoData);
  KeepOut k;
  k.zones = {box(1, 1, 3, 2)};
  CHECK(applyKeepOut(classes, k, 0.5) == 12);
  const auto keep = static_cast<std::uint8_t>(terrain::TerrainClass::KeepOut);
  const auto imp = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  CHECK(classes(2, 1) == keep);
  CHECK(classes(2, 2) == keep);
  CHECK(classes(1, 0) == imp);
  CHECK(classes(3, 3) == imp);
  CHECK(classes(0, 0) == 0);
  CHECK(classes(2, 4) == 0);
}
