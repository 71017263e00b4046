// The mission area (issue 24, core/planning/mission_area.hpp): window arithmetic on literal grids,
// the area's checks, the polygon mask, and a planner run on a window whose result, moved back,
// lies in the map's frame inside the area.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/planning/mission_area.hpp"
#include "dem_literals.hpp"

using namespace rover;

namespace {

std::vector<std::string> picture(const GridGeometry& g, const std::vector<std::uint8_t>& cells) {
  std::vector<std::string> out(g.rows, std::string(g.cols, '.'));
  for (int i = 0; i < g.cellCount(); ++i)
    if (cells[i]) out[g.cell(i).row][g.cell(i).col] = '#';
  return out;
}

// Records what a sink is handed.
struct Recorder : EventSink {
  std::vector<RoverPose> poses;
  std::vector<Point2> points;
  void roverPoses(std::int64_t, std::span<const RoverPose> p) override { poses.assign(p.begin(), p.end()); }
  void overlay(std::string_view, int, std::span<const Point2> p) override { points.assign(p.begin(), p.end()); }
};

}  // namespace

TEST_CASE("mission area: the window is the area's cells plus the margin, clipped to the map") {
  // A map of 8 columns × 10 rows of 1 m (8 × 10 m). The area x 2..5, y 1..4 covers columns 2..4
  // and, counting from the north (y 10 is row 0's top), rows 6..8.
  const GridGeometry map{10, 8, 1.0, 1.0};
  const MissionArea area = rectangleArea(2, 1, 5, 4);
  PlanningWindow w = planningWindow(map, area, 0);
  CHECK(w.col0 == 2);
  CHECK(w.row0 == 6);
  CHECK(w.grid.cols == 3);
  CHECK(w.grid.rows == 3);
  CHECK(w.origin == Eigen::Vector2d(2, 1));
  // A margin of 1 cell each way; on the south it stops at the map's edge (row 9 is the last).
  w = planningWindow(map, area, 1);
  CHECK(w.col0 == 1);
  CHECK(w.row0 == 5);
  CHECK(w.grid.cols == 5);
  CHECK(w.grid.rows == 5);
  CHECK(w.origin == Eigen::Vector2d(1, 0));
  // Every window cell is the map cell (row0 + r, col0 + c), at the same place once moved by the
  // origin: the one conversion pair of SPEC §0 holds in both frames.
  for (int r = 0; r < w.grid.rows; ++r)
    for (int c = 0; c < w.grid.cols; ++c)
      CHECK((cellToLocal(w.grid, {r, c}) + w.origin - cellToLocal(map, {w.row0 + r, w.col0 + c})).norm() < 1e-12);
  // Edges off the cell borders take every cell they touch: x 2.5..2.6 is column 2 alone.
  w = planningWindow(map, rectangleArea(2.5, 3.2, 2.6, 3.3), 0);
  CHECK(w.col0 == 2);
  CHECK(w.grid.cols == 1);
  CHECK(w.row0 == 6);
  CHECK(w.grid.rows == 1);
  // Cells of 0.5 m: x 2..5 is columns 4..9.
  const GridGeometry fine{20, 16, 0.5, 0.5};
  w = planningWindow(fine, area, 2);
  CHECK(w.col0 == 2);
  CHECK(w.grid.cols == 10);
  CHECK(w.row0 == 10);
  CHECK(w.grid.rows == 10);  // rows 12..17 and the margin: 10..19
  CHECK(w.origin == Eigen::Vector2d(1, 0));
  // The whole map as a window.
  CHECK(wholeMap(map).covers(map));
  CHECK(wholeMap(map).origin == Eigen::Vector2d::Zero());
}

TEST_CASE("mission area: bad areas are refused naming the field") {
  const GridGeometry map{10, 8, 1.0, 1.0};
  CHECK_NOTHROW(checkMissionArea(rectangleArea(0, 0, 8, 10), map));
  CHECK_THROWS_WITH_AS(checkMissionArea(rectangleArea(2, 1, 9, 4), map),
                       "the area's corner (9, 1) m lies off the map (8 × 10 m; local frame: metres from its "
                       "lower-left corner)",
                       Error);
  CHECK_THROWS_WITH_AS(checkMissionArea(rectangleArea(2, 1, 3, 4), map),
                       "the area is 1 × 3 m: it must span at least 2 cells (2 × 2 m) each way", Error);
  CHECK_THROWS_WITH_AS(checkMissionArea(rectangleArea(NAN, 1, 3, 4), map),
                       "the area's coordinates must be finite numbers", Error);
  CHECK_THROWS_WITH_AS(checkMissionArea(rectangleArea(5, 1, 2, 4), map),
                       "the area's x1, y1 must be greater than its x0, y0", Error);
  CHECK_THROWS_WITH_AS(checkMissionArea(polygonArea({{1, 1}, {5, 5}}), map),
                       "a polygon area needs 3 to 1024 vertices, not 2", Error);
  // Three points on one line: no surface.
  CHECK_THROWS_WITH_AS(checkMissionArea(polygonArea({{1, 1}, {3, 3}, {5, 5}}), map),
                       "the polygon's surface is under 4 cells (it is degenerate or self-cancelling)", Error);
  try {
    checkMissionArea(rectangleArea(2, 1, 9, 4), map);
  } catch (const Error& e) {
    CHECK(e.field() == "area");
    CHECK(e.code() == ErrorCode::InvalidInput);
  }
  // A window over 4096² cells: the area is too big to plan on.
  const GridGeometry big{5000, 5000, 1.0, 1.0};
  CHECK_THROWS_WITH_AS(checkMissionArea(rectangleArea(0, 0, 4200, 4200), big),
                       "the area's planning window is 4204 × 4204 cells (with a margin of 4 cells), more than "
                       "16777216 (4096 × 4096): choose a smaller area",
                       Error);
  CHECK_NOTHROW(checkMissionArea(rectangleArea(100, 100, 250, 250), big));
  // A GeoJSON-style closed ring loses its repeated vertex.
  CHECK(polygonArea({{1, 1}, {5, 1}, {5, 5}, {1, 1}}).outline.size() == 3);
}

TEST_CASE("mission area: outside a polygon is keep-out, inside is where the mass lies") {
  // A window of 8 × 6 cells of 1 m; the area a right triangle with its legs on cell borders.
  //   y 6 ┌────────┐
  //       │        │
  //       │ ◣      │   triangle (1,1) (7.5,1) (1,5.5)
  //   y 0 └────────┘
  const GridGeometry g{6, 8, 1.0, 1.0};
  PlanningWindow w;
  w.grid = g;
  const MissionArea tri = polygonArea({{1, 1}, {7.5, 1}, {1, 5.5}});
  const Polygon outside = outsideArea(tri, w);
  // The cells the hypotenuse crosses are keep-out too (any part outside), so inside are only
  // cells wholly in the triangle.
  CHECK(picture(g, polygonCells(g, {outside})) == std::vector<std::string>{
                                                       "########",
                                                       "########",
                                                       "#..#####",
                                                       "#...####",
                                                       "#.....##",
                                                       "########",
                                                   });
  CHECK(picture(g, cellsInArea(tri, g)) == std::vector<std::string>{
                                               "........",
                                               "........",
                                               ".##.....",
                                               ".###....",
                                               ".#####..",
                                               "........",
                                           });
  // A rectangle on cell borders keeps every cell it covers.
  const MissionArea rect = rectangleArea(2, 1, 5, 4);
  CHECK(picture(g, cellsInArea(rect, g)) == std::vector<std::string>{
                                                "........",
                                                "........",
                                                "..###...",
                                                "..###...",
                                                "..###...",
                                                "........",
                                            });
}

TEST_CASE("mission area: inputs move into the window, results and events back into the map") {
  const GridGeometry map{10, 8, 1.0, 1.0};
  const MissionArea area = rectangleArea(2, 1, 5, 4);
  const PlanningWindow w = planningWindow(map, area, 1);  // origin (1, 0)
  std::vector<RoverStart> rovers{{{3.5, 2.5}, 0.3}};
  KeepOut zones;
  zones.zones = {{{{2, 2}, {3, 2}, {3, 3}}}};
  moveIntoWindow(rovers, zones, w, area);
  CHECK(rovers[0].position == Eigen::Vector2d(2.5, 2.5));
  CHECK(rovers[0].heading == 0.3);
  REQUIRE(zones.zones.size() == 2);
  CHECK(zones.zones[0][0][0] == Eigen::Vector2d(1, 2));
  // The added zone: the window (grown by a cell) with the area, in the window's frame, as a hole.
  CHECK(zones.zones[1].size() == 2);
  CHECK(zones.zones[1][1][0] == Eigen::Vector2d(1, 1));
  CHECK(zones.zoneAt({2.5, 2.5}) < 0);  // the start: inside the area
  CHECK(zones.zoneAt({0.5, 0.5}) == 1);  // the margin: outside it

  PlanResult r;
  r.tracks.push_back({});
  r.tracks[0].points = {{2.5, 2.5}};
  r.tracks[0].samples.push_back({});
  r.tracks[0].samples[0].position = {1, 1};
  r.targets.push_back({});
  r.targets[0].position = {2, 2};
  r.incidents.push_back({});
  r.incidents[0].position = {3, 3};
  r.overlays.push_back({"route", -1, {{0, 0}}});
  shiftResult(r, w.origin);
  CHECK(r.tracks[0].points[0] == Eigen::Vector2d(3.5, 2.5));
  CHECK(r.tracks[0].samples[0].position == Eigen::Vector2d(2, 1));
  CHECK(r.targets[0].position == Eigen::Vector2d(3, 2));
  CHECK(r.incidents[0].position == Eigen::Vector2d(4, 3));
  CHECK(r.overlays[0].points[0] == Eigen::Vector2d(1, 0));

  Recorder rec;
  ShiftedSink sink(rec, w.origin);
  const RoverPose pose{0, 2.5, 2.5, 0.0};
  sink.roverPoses(1, std::span<const RoverPose>(&pose, 1));
  CHECK(rec.poses.at(0).x == 3.5);
  CHECK(rec.poses.at(0).y == 2.5);
  const Point2 p{0.5, 0.5};
  sink.overlay("path", 0, std::span<const Point2>(&p, 1));
  CHECK(rec.points.at(0).x == 1.5);
  CHECK(rec.points.at(0).y == 0.5);
}

TEST_CASE("mission area: coverage planned on a window stays in the area, in the map's frame") {
  // A flat 16 × 12 m map of 0.5 m cells; the area a quadrilateral in its middle. The planner sees
  // only the window; its track, moved back, lies inside the area.
  const terrain::Dem map = test::demFrom(24, 32, 0.5, [](double, double) { return 0.0; });
  const MissionArea area = polygonArea({{4, 3}, {11, 3}, {12, 9}, {5, 8}});
  checkMissionArea(area, map.geometry());
  const PlanningWindow w = planningWindow(map.geometry(), area);
  terrain::Dem window;
  window.z = Raster<float>(w.grid, 0.0f);
  PlanningProblem problem;
  problem.dem = std::make_shared<terrain::Dem>(window);
  problem.world = coverage::worldFromDem(window, 0.5, {});
  problem.rovers = {{{6.1, 5.1}, 0.0}};
  moveIntoWindow(problem.rovers, problem.keepOut, w, area);
  const auto planner = coverage::makeCoveragePlanner();
  const ParamSet params{{"frontier", true}, {"coverage", 1.0}};
  planner->validate(problem, params);
  PlanResult r = planner->run(problem, params, nullptr, nullptr);
  shiftResult(r, w.origin);
  const Track& t = r.tracks.at(0);
  CHECK((t.points.front() - Eigen::Vector2d(6.1, 5.1)).norm() < 0.5);  // the start, in the map's frame
  CHECK(t.points.size() > 100);
  for (const auto& p : t.points) CHECK(insidePolygon({area.outline}, p));
}
