// The team planner's global layer (traversal_lattice): reachability before the route, guide paths
// under RRT*, timed coordination, and the paper mode kept as it was. Maps are drawn as pictures:
// one character is one metre (4 × 4 cells of 0.25 m), '#' a 1 m high block (a vertical step, so
// impassable), '.' flat ground at 0.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/planning/departure.hpp"
#include "core/team/coordination.hpp"
#include "core/team/team_mission.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;

namespace {

using test::demFromPicture;

// A crater ringed by a wall on a 24 × 24 m site: its floor (x 13..21, y 8..16) holds most of the
// probability but cannot be reached from the south-west where the team starts.
const std::vector<std::string> kCrater = {
    "........................",  // y 24
    "........................",
    "........................",
    "........................",
    "........................",
    "........................",
    "........................",
    "............##########..",  // y 17
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............#........#..",
    "............##########..",  // y 7
    "........................",
    "........................",
    "........................",
    "........................",
    "........................",
    "........................",
    "........................",  // y 0
};

bool onFloor(const Eigen::Vector2d& p) { return p.x() > 13 && p.x() < 21 && p.y() > 8 && p.y() < 16; }

// Ten times the mass per cell on the crater floor.
Raster<float> craterPdm(const terrain::Dem& dem) {
  const GridGeometry& g = dem.geometry();
  Raster<float> pdm(g, 0.0f);
  double sum = 0;
  for (int i = 0; i < g.cellCount(); ++i) {
    const double w = onFloor(cellToLocal(g, g.cell(i))) ? 10.0 : 1.0;
    pdm.at(i) = static_cast<float>(w);
    sum += w;
  }
  for (int i = 0; i < g.cellCount(); ++i) pdm.at(i) = static_cast<float>(pdm.at(i) / sum);
  return pdm;
}

std::uint8_t at(const Raster<std::uint8_t>& r, const Eigen::Vector2d& p) {
  const CellIndex c = *localToCell(r.geometry, p);
  return r(c.row, c.col);
}

}  // namespace

TEST_CASE("team planner: a target inside a walled crater is reported unreachable and never chosen") {
  const terrain::Dem dem = demFromPicture(kCrater);
  const auto classes = terrain::traversability(dem).classes;
  const CoordinationParams cp;
  const TraversalLattice lattice = makeLattice(dem, classes, cp);
  const Raster<std::uint8_t> reach = lattice.reachable({{4, 4}});
  CHECK(at(reach, {2, 2}) == 1);
  CHECK(at(reach, {17, 12}) == 0);  // the floor
  CHECK(at(reach, {23, 20}) == 1);  // round the crater, east of it

  TeamMissionParams p;
  p.route.targets = 6;
  p.coordination.threads = 2;
  const Raster<float> pdm = craterPdm(dem);
  const std::vector<Pose> starts{{4, 4, 0}, {6, 4, 0}};
  const TeamMissionResult r = runTeamMission(dem, pdm, starts, p, false);
  // Reported up front: the floor's area (8 × 8 m less the wall's impassable margin, 56 m²) and
  // the flat middle of the wall's top (36 m round × 0.5 m), and the floor's mass.
  CHECK(r.reachability.unreachableAreaM2 == doctest::Approx(56.25 + 18.0));
  CHECK(r.reachability.unreachableMass > 0.3);
  CHECK(r.reachability.unreachableSearchCells >= 1);
  // The search cell x 15..20, y 10..15 lies on the floor: never a target, and no goal on the floor.
  const CellIndex floorCell{r.grid.rows() - 1 - 2, 3};
  CHECK_FALSE(r.grid.passable(floorCell));
  CHECK(std::find(r.route.cells.begin(), r.route.cells.end(), floorCell) == r.route.cells.end());
  for (const auto& t : r.plan.trajectories)
    for (const auto& s : t.samples) CHECK_FALSE(onFloor({s.x, s.y}));
  CHECK(r.metrics.targetsShort == 0);
  CHECK(r.metrics.collisions == 0);
  // The plan says so: completed with warnings.
  const auto warnings = missionWarnings(r);
  CHECK(std::any_of(warnings.begin(), warnings.end(),
                    [](const std::string& w) { return w.find("cannot be reached") != std::string::npos; }));

  // Paper mode: the same ground is reported, but its route still aims at the floor (today's).
  p.coordination.mode = CoordinationMode::Paper;
  const TeamMissionResult paper = runTeamMission(dem, pdm, starts, p, false);
  CHECK(paper.reachability.unreachableMapCells == r.reachability.unreachableMapCells);
  CHECK(std::find(paper.route.cells.begin(), paper.route.cells.end(), floorCell) != paper.route.cells.end());
}

TEST_CASE("team planner: a wall longer than the old 2 m box is passed round") {
  // 20 × 12 m; a 9 m wall at x 10..11 with a 3 m gap at the south edge. Start (3, 6), goal
  // (17, 6): the old box is y 4..8, wholly blocked.
  const std::vector<std::string> picture = {
      "..........#.........",  // y 12
      "..........#.........",
      "..........#.........",
      "..........#.........",
      "..........#.........",
      "..........#.........",
      "..........#.........",
      "..........#.........",
      "..........#.........",  // y 3
      "....................",
      "....................",
      "....................",  // y 0
  };
  const terrain::Dem dem = demFromPicture(picture);
  const auto classes = terrain::traversability(dem).classes;
  const Eigen::Vector2d start(3, 6), goal(17, 6);
  // The paper's boxed RRT* cannot get there.
  const PathResult boxed = planPath(dem, classes, start, 0.0, goal, teamRrtDefaults());
  CHECK(boxed.status != PathStatus::Exact);

  std::vector<RoverTask> tasks(1);
  tasks[0].start = {start.x(), start.y(), 0};
  tasks[0].legs.push_back({goal, {}, 0});
  CoordinationParams p;
  const CoordinationResult r = coordinate(dem, classes, tasks, p, 5);
  REQUIRE(r.legs.size() == 1);
  CHECK(r.legs[0].status == LegStatus::Reached);
  const auto& s = r.trajectories[0].samples;
  CHECK((Eigen::Vector2d(s.back().x, s.back().y) - goal).norm() < 0.5);
  // The planned path is valid edge by edge (the simulated rover may cut a corner by a few
  // centimetres; it never crosses the wall itself).
  const TerrainEdgeModel model(dem, classes, {{0, 0}, {20, 12}}, p.rrt.attitudeLimit, 0.0625);
  const auto& path = r.paths[0];
  for (std::size_t i = 0; i + 1 < path.size(); ++i) CHECK(model.edgeValid(path[i], path[i + 1]));
  double lowest = 1e9;
  for (const auto& x : s) {
    lowest = std::min(lowest, x.y);
    CHECK_FALSE((x.x >= 10 && x.x <= 11 && x.y >= 3));
  }
  CHECK(lowest < 3.0);  // through the gap

  p.mode = CoordinationMode::Paper;  // today's: the leg ends short
  const CoordinationResult paper = coordinate(dem, classes, tasks, p, 5);
  CHECK(paper.legs[0].status != LegStatus::Reached);
}

TEST_CASE("team planner: two rovers crossing head-on keep the safety distance and both arrive") {
  const terrain::Dem dem = test::demFrom(80, 160, 0.25, [](double, double) { return 0.0; });
  const auto classes = terrain::traversability(dem).classes;
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {5, 10, 0};
  tasks[0].legs.push_back({{30, 10}, {}, 0});
  tasks[1].start = {35, 10, M_PI};
  tasks[1].legs.push_back({{10, 10}, {}, 0});
  for (CoordinationMode mode : {CoordinationMode::Timed, CoordinationMode::Paper}) {
    CAPTURE(enumName(mode));
    CoordinationParams p;
    p.mode = mode;
    const CoordinationResult r = coordinate(dem, classes, tasks, p, 11);
    const SeparationReport sep = checkSeparation(r.trajectories, p.safetyDistance);
    CHECK(sep.conflicts.empty());
    CHECK(sep.minimumDistance >= p.safetyDistance);
    REQUIRE(r.legs.size() == 2);
    CHECK(r.legs[0].status == LegStatus::Reached);
    CHECK(r.legs[1].status == LegStatus::Reached);
    const auto& a = r.trajectories[0].samples.back();
    const auto& b = r.trajectories[1].samples.back();
    CHECK((Eigen::Vector2d(a.x, a.y) - Eigen::Vector2d(30, 10)).norm() < 0.5);
    CHECK((Eigen::Vector2d(b.x, b.y) - Eigen::Vector2d(10, 10)).norm() < 0.5);
  }
}

TEST_CASE("team planner: a conflict is resolved by starting later, without re-planning") {
  // Rover 1 crosses rover 0's line; the timed mode delays it instead of planning again.
  const terrain::Dem dem = test::demFrom(120, 120, 0.25, [](double, double) { return 0.0; });
  const auto classes = terrain::traversability(dem).classes;
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {2, 15, 0};
  tasks[0].legs.push_back({{28, 15}, {}, 0});
  tasks[1].start = {15, 2, M_PI / 2};
  tasks[1].legs.push_back({{15, 28}, {}, 0});
  const CoordinationResult r = coordinate(dem, classes, tasks, CoordinationParams{}, 3);
  REQUIRE(r.legs.size() == 2);
  CHECK(r.legs[1].status == LegStatus::Reached);
  CHECK(r.legs[1].replans == 0);
  CHECK(r.legs[1].waits == 1);
  CHECK(r.legs[1].waitTime > 0);
  CHECK(r.conflicts.empty());
  CHECK(r.rrtCalls == 2);  // the two planned-ahead legs, nothing more
}

TEST_CASE("team planner: paper mode reproduces today's mission on a fixed case") {
  // Figures printed by the unmodified build (/work/main, commit b26dc8b) for this very case: the
  // rolling 30 × 30 m site of test_team_coordination.cpp, 3 rovers, 6 targets, seed 1.
  const terrain::Dem dem = test::demFrom(120, 120, 0.25, [](double x, double y) {
    return 0.35 * std::sin(x / 2.3) * std::cos(y / 3.1) + 0.02 * x;
  });
  TeamMissionParams p;
  p.route.targets = 6;
  p.coordination.threads = 2;
  p.coordination.mode = CoordinationMode::Paper;
  const std::vector<Pose> starts{{12, 12, 0}, {15, 12, 0}, {12, 15, 0}};
  const TeamMissionResult a = runTeamMission(dem, uniformPdm(dem), starts, p, false);
  CHECK(a.metrics.meanTrajectoryM == doctest::Approx(30.834095007066548).epsilon(1e-12));
  CHECK(a.metrics.samples == 3801);
  CHECK(a.metrics.targetsReached == 18);
  CHECK(a.metrics.replans == 24);
  CHECK(a.metrics.waits == 2);
  CHECK(a.metrics.rrtCalls == 42);
  REQUIRE(a.plan.trajectories.size() == 3);
  CHECK(a.plan.trajectories[0].samples.size() == 1210);
  CHECK(a.plan.trajectories[1].samples.size() == 1219);
  CHECK(a.plan.trajectories[2].samples.size() == 1372);
  CHECK(a.plan.trajectories[2].samples.back().x == doctest::Approx(13.934953753633506).epsilon(1e-12));
  CHECK(a.plan.trajectories[2].samples.back().y == doctest::Approx(23.891397209547701).epsilon(1e-12));
}

TEST_CASE("team planner: a rover at the end of a dead-end lane leaves after the team mate in front of it") {
  // A lane 2 m wide (x 1..3, walls 1 m high) closed at its south end, opening north onto open
  // ground. Rover 0 stands at the dead end, rover 1 in front of it: on open ground both could
  // leave at once and rover 0 is planned first (index order), but no path past its standing team
  // mate keeps the safety distance in the lane. Over the ground the lattice reaches (issue 25:
  // on the Kepler site 9 of 64 rovers between the crater wall and their team mates lost every leg
  // so) rover 0 leaves after rover 1, and both arrive.
  std::vector<std::string> picture(14, std::string(18, '.'));
  for (int y = 0; y < 9; ++y)
    for (int x : {0, 3}) picture[13 - y][x] = '#';
  picture[13][1] = picture[13][2] = '#';  // the dead end, y 0..1
  const terrain::Dem dem = demFromPicture(picture);
  const auto classes = terrain::traversability(dem).classes;
  CoordinationParams p;
  p.threads = 2;
  const TraversalLattice lattice = makeLattice(dem, classes, p);
  const std::vector<Eigen::Vector2d> starts{{2, 2}, {2, 4.5}};
  const Raster<std::uint8_t> ground = lattice.reachable(starts);
  CHECK(planning::departureOrder(starts, p.safetyDistance).order == std::vector<int>{0, 1});
  const GroundDeparture over = departureOverGround(starts, p.safetyDistance, ground);
  CHECK(over.ground);  // the lattice's ground, not the open-ground fallback
  const planning::Departure& d = over.departure;
  CHECK(d.order == std::vector<int>{1, 0});
  CHECK(d.firstRound == 1);

  std::vector<RoverTask> tasks(2);
  for (int k = 0; k < 2; ++k) tasks[k].start = {starts[k].x(), starts[k].y(), M_PI / 2};
  tasks[0].legs.push_back({{9, 11}, {}, 0});
  tasks[1].legs.push_back({{12, 11}, {}, 0});
  const CoordinationResult r = coordinate(dem, classes, tasks, p, 3, nullptr, nullptr, &lattice);
  REQUIRE(r.legs.size() == 2);
  for (const LegRecord& leg : r.legs) {
    CAPTURE(leg.rover);
    CHECK(leg.status == LegStatus::Reached);
  }
  CHECK(r.conflicts.empty());
}

TEST_CASE("team planner: the departure ground falls back to open ground when it lets a rover out nowhere") {
  // A 12 × 12 m map: the way-out test's margin (ten safety distances past the starts) lies off
  // the map, so over the lattice's ground no rover has a way out; the team leaves as on open
  // ground instead of being refused.
  const terrain::Dem dem = demFromPicture(std::vector<std::string>(12, std::string(12, '.')));
  const auto classes = terrain::traversability(dem).classes;
  const CoordinationParams p;
  const TraversalLattice lattice = makeLattice(dem, classes, p);
  const std::vector<Eigen::Vector2d> starts{{5, 6}, {7, 6}};
  const Raster<std::uint8_t> ground = lattice.reachable(starts);
  CHECK_FALSE(planning::departureOrder(starts, p.safetyDistance, groundIn(ground)).boxedIn.empty());
  const GroundDeparture over = departureOverGround(starts, p.safetyDistance, ground);
  CHECK_FALSE(over.ground);
  CHECK(over.departure.order == planning::departureOrder(starts, p.safetyDistance).order);
  CHECK(over.departure.boxedIn.empty());
}
