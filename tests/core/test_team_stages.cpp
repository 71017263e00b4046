// The team planner's stages, each alone (issue 10): the route generator on a literal search grid,
// the task builder and the leg planner on DEMs drawn as pictures, the rover simulator, and the
// coordinator driven by a fake leg planner and a fake rover. Pictures: one character is one metre
// (4 × 4 cells of 0.25 m), '#' a 1 m high block (a vertical step, so impassable), '.' flat ground.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/team/coordinator.hpp"
#include "core/team/formation.hpp"
#include "core/team/leg_planner.hpp"
#include "core/team/leg_simulator.hpp"
#include "core/team/plan_ahead.hpp"
#include "core/team/route_generator.hpp"
#include "core/team/task_builder.hpp"
#include "core/team/team_incidents.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;

namespace {

using test::demFromPicture;

// A search grid of 1 m cells from a picture: a digit is the cell's mass, '#' impassable, 'S' the
// start (mass 0).
SearchGrid searchGridFrom(const std::vector<std::string>& picture) {
  const GridGeometry g{static_cast<int>(picture.size()), static_cast<int>(picture[0].size()), 1, 1};
  Raster<float> pdm(g, 0.0f);
  Raster<std::uint8_t> classes(g, 0);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      const char ch = picture[r][c];
      if (ch == '#') classes(r, c) = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
      if (ch >= '0' && ch <= '9') pdm(r, c) = static_cast<float>(ch - '0');
    }
  return makeSearchGrid(pdm, classes, 1.0);
}

std::vector<CellIndex> cells(std::initializer_list<std::pair<int, int>> rc) {
  std::vector<CellIndex> out;
  for (auto [r, c] : rc) out.push_back({r, c});
  return out;
}

Route routeThrough(const std::vector<Eigen::Vector2d>& centres) {
  Route r;
  r.centres = centres;
  for (std::size_t i = 0; i < centres.size(); ++i) r.cells.push_back({0, static_cast<int>(i)});
  return r;
}

// A fake leg planner: a straight line to the goal whatever the ground and the keep-out zones,
// except for goals it is told are invalid or cannot be reached.
class StraightLinePlanner final : public LegPlanner {
 public:
  std::vector<Eigen::Vector2d> invalidGoals, unreachableGoals;
  PathResult plan(const Eigen::Vector2d& from, double, const Eigen::Vector2d& goal, std::uint64_t,
                  const std::vector<KeepOutZone>&, const CancelToken*) const override {
    PathResult r;
    auto near = [&](const std::vector<Eigen::Vector2d>& v) {
      return std::any_of(v.begin(), v.end(), [&](const auto& p) { return (p - goal).norm() < 1e-9; });
    };
    if (near(invalidGoals)) {
      r.status = PathStatus::InvalidGoal;
    } else if (near(unreachableGoals)) {
      r.status = PathStatus::NoSolution;
    } else {
      r.status = PathStatus::Exact;
      r.waypoints = {from, goal};
    }
    return r;
  }
  bool edgeValid(const Eigen::Vector2d&, const Eigen::Vector2d&) const override { return true; }
  bool canStop(const Eigen::Vector2d&) const override { return true; }
};

// A fake rover: drives the waypoints in straight lines at 0.5 m/s, sampled at 10 Hz.
class StraightLineRover final : public LegSimulator {
 public:
  Trajectory drive(const std::vector<Eigen::Vector2d>& waypoints, const Pose& start,
                   double startTime, std::uint64_t, const CancelToken*) const override {
    Trajectory t;
    TrajectorySample s;
    s.time = startTime;
    s.x = start.x;
    s.y = start.y;
    s.heading = start.heading;
    t.samples.push_back(s);
    for (const Eigen::Vector2d& w : waypoints) {
      const Eigen::Vector2d a(s.x, s.y);
      const double len = (w - a).norm();
      const int steps = static_cast<int>(std::ceil(len / 0.05));
      for (int i = 1; i <= steps; ++i) {
        const Eigen::Vector2d p = a + (w - a) * (static_cast<double>(i) / steps);
        s.distance += (p - Eigen::Vector2d(s.x, s.y)).norm();
        s.time += 0.1;
        s.x = p.x();
        s.y = p.y();
        s.heading = std::atan2(w.y() - a.y(), w.x() - a.x());
        s.speed = 0.5;
        t.samples.push_back(s);
      }
    }
    t.waypointsReached = waypoints.size();
    return t;
  }
};

// Rover 0 drives east along y = 5, rover 1 north along x = 5: both reach (5, 5) at 10 s.
std::vector<RoverTask> crossingTasks() {
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {0, 5, 0};
  tasks[0].legs.push_back({{10, 5}, {}, 0});
  tasks[1].start = {5, 0, M_PI / 2};
  tasks[1].legs.push_back({{5, 10}, {}, 0});
  return tasks;
}

Eigen::Vector2d endOf(const Trajectory& t) { return {t.samples.back().x, t.samples.back().y}; }

}  // namespace

TEST_CASE("stages: the route generators climb the masses, skip the walled cell, mow the rows") {
  // The team starts at S; the hill climb takes the highest neighbour each time (9, 6, 5, 4, 3, 2,
  // 1) and never enters '#'; the lawnmower runs the start row east, then the rows above
  // alternately west and east.
  const SearchGrid grid = searchGridFrom({
      "234",
      "1#5",
      "S96",
  });
  const CellIndex start{2, 0};
  const auto climb = cells({{2, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}, {0, 0}, {1, 0}});
  RouteParams p;
  p.targets = 7;
  CHECK(LhcRoute(p).generate(grid, start).cells == climb);
  CHECK(LhcGwConvRoute(p).generate(grid, start).cells == climb);
  CHECK(makeRouteGenerator(RouteMethod::Lhc, p)->generate(grid, start).cells == climb);
  CHECK(LawnmowerRoute(7).generate(grid, start).cells ==
        cells({{2, 1}, {2, 2}, {1, 2}, {1, 0}, {0, 0}, {0, 1}, {0, 2}}));
  // The start cell is the one holding the rovers' centroid.
  CHECK(teamStartCell(grid, {{0.2, 0.3, 0}, {0.6, 0.5, 0}}).row == 2);
  CHECK(grid.cellAt({2.5, 2.5}).col == 2);
  CHECK(grid.cellAt({2.5, 2.5}).row == 0);
}

TEST_CASE("stages: the slot task builder moves a goal off a wall and leaves a walled target out") {
  // Target 0 (7, 3.5) lies on the west step of the block at x 7..9, y 3..4: its goal moves to the
  // nearest ground a rover may stop on. Target 1 (2.5, 4) lies on the plateau in the west, which
  // the team cannot reach (marked so below): nothing valid and reachable within half a
  // footprint, so the rover gets no leg there.
  const terrain::Dem dem = demFromPicture({
      "#####.......",  // y 7
      "#####.......",
      "#####.......",
      "#####..##...",  // y 4
      "#####..##...",  // y 3
      "#####.......",
      "#####.......",
      "#####.......",  // y 0
  });
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  const Route route = routeThrough({{7, 3.5}, {2.5, 4}});
  const std::vector<Pose> starts{{10, 1, 0}};
  Raster<std::uint8_t> reachable(dem.geometry(), 1);
  for (int i = 0; i < reachable.geometry.cellCount(); ++i)
    if (cellToLocal(reachable.geometry, reachable.geometry.cell(i)).x() < 5) reachable.at(i) = 0;
  const std::vector<RoverTask> tasks =
      SlotTasks(dem, classes, p, &reachable).build(starts, route, nullptr);
  REQUIRE(tasks.size() == 1);
  REQUIRE(tasks[0].legs.size() == 1);
  const Leg& leg = tasks[0].legs[0];
  CHECK(leg.target == 0);
  CHECK((leg.goal - Eigen::Vector2d(7, 3.5)).norm() <= p.footprint / 2);
  CHECK((leg.goal - Eigen::Vector2d(7, 3.5)).norm() > 0.1);
  CHECK(wholeMapModel(dem, classes, p.coordination.rrt).turnValid(leg.goal));
  // The free function is the same builder.
  CHECK(teamSearchTasks(dem, classes, starts, route, p, &reachable)[0].legs[0].goal == leg.goal);
  // Without the reachability mask the plateau top is ground a rover may stop on.
  CHECK(SlotTasks(dem, classes, p, nullptr).build(starts, route, nullptr)[0].legs.size() == 2);
}

TEST_CASE("stages: a slot inside a wall beside the target takes free ground elsewhere in its search cell") {
  // The target (7.5, 5.5) lies 0.5 m from a wall that steps in to x = 7 south of y = 4, as on the
  // Kepler site's crater floor edge, where all 5 no-slots of N = 5 were such targets. The slots
  // are the centre, then (-1.67, +1.67), (+1.67, +1.67), (-1.67, -1.67), (+1.67, -1.67): the
  // last one (9.17, 3.83) lies in the wall, and the ground within half a footprint of it is all
  // closer than the goal spacing to the goals its team mates took first. The search cell
  // (x 5..10, y 3..8) still has free ground on its west side.
  std::vector<std::string> picture(10, std::string(12, '.'));
  for (int y = 0; y < 10; ++y)
    for (int x = y < 4 ? 7 : 8; x < 12; ++x) picture[9 - y][x] = '#';
  const terrain::Dem dem = demFromPicture(picture);
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  const Raster<std::uint8_t> reachable = makeLattice(dem, classes, p.coordination).reachable({{2, 5}});
  const Eigen::Vector2d centre(7.5, 5.5);
  const std::vector<Pose> starts{{1, 1, 0}, {1, 3, 0}, {1, 5, 0}, {1, 7, 0}, {1, 9, 0}};
  const std::vector<RoverTask> tasks =
      SlotTasks(dem, classes, p, &reachable).build(starts, routeThrough({centre}), nullptr);
  REQUIRE(tasks.size() == 5);
  const double spacing = goalSpacing(p.coordination);
  const std::vector<Eigen::Vector2d> slots = goalSlots(5, p.footprint, spacing);
  REQUIRE((slots[4] - Eigen::Vector2d(5.0 / 3, -5.0 / 3)).norm() < 1e-9);
  std::vector<Eigen::Vector2d> goals;
  for (const RoverTask& t : tasks) {
    REQUIRE(t.legs.size() == 1);  // every rover has a leg: no slot without ground
    goals.push_back(t.legs[0].goal);
  }
  const TerrainEdgeModel model = wholeMapModel(dem, classes, p.coordination.rrt);
  const double stop = stopCircleRadius(p.coordination.controller);
  // The half-footprint search of the last slot alone finds nothing beside the others' goals.
  const std::vector<Eigen::Vector2d> others(goals.begin(), goals.begin() + 4);
  CHECK_FALSE(nearestValid(model, centre + slots[4], p.footprint / 2, spacing, others, &reachable, stop));
  // Its goal is in the search cell, on ground to stop and turn on, apart from every team mate's.
  CHECK((goals[4] - centre).cwiseAbs().maxCoeff() <= p.footprint / 2);
  CHECK(turnableAround(model, goals[4], stop));
  for (std::size_t a = 0; a < goals.size(); ++a)
    for (std::size_t b = a + 1; b < goals.size(); ++b) CHECK((goals[a] - goals[b]).norm() >= spacing - 1e-9);
  // The paper mode keeps its slots: that rover gets no leg there.
  TeamMissionParams paper = p;
  paper.coordination.mode = CoordinationMode::Paper;
  CHECK(SlotTasks(dem, classes, paper, &reachable).build(starts, routeThrough({centre}), nullptr)[4].legs.empty());
}

TEST_CASE("stages: the hybrid task builder adds coverage moves inside the footprint") {
  const terrain::Dem dem = demFromPicture(std::vector<std::string>(12, std::string(12, '.')));
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  const Route route = routeThrough({{6, 6}});
  const std::vector<RoverTask> tasks =
      HybridTasks(dem, classes, p, nullptr).build({{1, 1, 0}, {2.5, 1, 0}}, route, nullptr);
  REQUIRE(tasks.size() == 2);
  for (const RoverTask& t : tasks) {
    REQUIRE(t.legs.size() == 2);  // the slot leg, then the coverage moves
    CHECK(t.legs[0].via.empty());
    REQUIRE(t.legs[1].via.size() >= 2);
    CHECK(t.legs[1].goal == t.legs[1].via.back());
    for (const auto& v : t.legs[1].via) CHECK((v - Eigen::Vector2d(6, 6)).cwiseAbs().maxCoeff() < 2.5);
  }
}

TEST_CASE("stages: team mates' goals stay apart by the safety distance plus both acceptance circles") {
  // Five rovers in a 2.5 m footprint: the formation slots are 0.83 m apart, so the builder moves
  // them. Rovers may stop anywhere in their acceptance circle, so goals only the safety distance
  // apart could leave two rovers closer than it, and a rover parked there for good would block
  // its team mate's leg for ever (the old rule gave pairs 1.0–1.5 m apart here).
  const terrain::Dem dem = demFromPicture(std::vector<std::string>(12, std::string(12, '.')));
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  p.footprint = 2.5;
  const std::vector<Pose> starts{{1, 0.5, 0}, {3, 0.5, 0}, {5, 0.5, 0}, {7, 0.5, 0}, {9, 0.5, 0}};
  const std::vector<RoverTask> tasks =
      SlotTasks(dem, classes, p, nullptr).build(starts, routeThrough({{6, 6}}), nullptr);
  const double apart = p.coordination.safetyDistance + 2 * p.coordination.controller.acceptanceRadius;
  std::vector<Eigen::Vector2d> goals;
  for (const RoverTask& t : tasks)
    for (const Leg& leg : t.legs) goals.push_back(leg.goal);
  REQUIRE(goals.size() >= 3);
  for (std::size_t a = 0; a < goals.size(); ++a)
    for (std::size_t b = a + 1; b < goals.size(); ++b) CHECK((goals[a] - goals[b]).norm() >= apart - 1e-9);
}

TEST_CASE("stages: every fixed point of a hybrid leg is ground a rover may stop on") {
  // Coverage cells are free when most of their DEM cells are: the 1 m blocks in the footprint
  // round (6, 6) leave cells whose centres sit on a step. Each fixed point moves off it (or is
  // left out), so a hybrid leg never ends on a goal no rover may stop on.
  const terrain::Dem dem = demFromPicture({
      "............",
      "............",
      "............",
      "....#..#....",  // y 8
      "............",
      "......#.....",  // y 6
      "....#...#...",
      "............",  // y 4
      "............",
      "............",
      "............",
      "............",
  });
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  const TerrainEdgeModel model = wholeMapModel(dem, classes, p.coordination.rrt);
  const std::vector<RoverTask> tasks =
      HybridTasks(dem, classes, p, nullptr).build({{1, 1, 0}, {2.5, 1, 0}}, routeThrough({{6, 6}}), nullptr);
  std::size_t fixed = 0;
  for (const RoverTask& t : tasks)
    for (const Leg& leg : t.legs) {
      CHECK(model.turnValid(leg.goal));
      for (const auto& v : leg.via) CHECK(model.turnValid(v));
      fixed += leg.via.size();
    }
  CHECK(fixed >= 8);
}

TEST_CASE("stages: the guided leg planner goes round a wall the boxed planner cannot") {
  // A 6 m wall between start (2, 5) and goal (7, 5): the start/goal box grown by 2 m (y 3..7)
  // lies inside its span (y 2..8), so the boxed RRT* cannot get round; the guide finds the way.
  const terrain::Dem dem = demFromPicture({
      "..........",  // y 9
      "..........",
      "....#.....",  // y 7
      "....#.....",
      "....#.....",
      "....#.....",
      "....#.....",
      "....#.....",  // y 2
      "..........",
      "..........",  // y 0
  });
  const auto classes = terrain::traversability(dem).classes;
  const CoordinationParams cp;
  const BoxedRrtPlanner boxed(dem, classes, cp.rrt, cp.weights);
  CHECK(boxed.plan({2, 5}, 0, {7, 5}, 3, {}, nullptr).status != PathStatus::Exact);
  const TraversalLattice lattice = makeLattice(dem, classes, cp);
  const GuidedRrtPlanner guided(dem, classes, lattice, cp.rrt, cp.weights, cp.corridorRadius);
  const PathResult r = guided.plan({2, 5}, 0, {7, 5}, 3, {}, nullptr);
  REQUIRE(r.status == PathStatus::Exact);
  CHECK((r.waypoints.back() - Eigen::Vector2d(7, 5)).norm() < 1e-9);
  for (std::size_t i = 0; i + 1 < r.waypoints.size(); ++i)
    CHECK(guided.edgeValid(r.waypoints[i], r.waypoints[i + 1]));
  CHECK_FALSE(guided.canStop({4.0, 5}));  // on the wall's step
  CHECK(guided.canStop({2, 5}));
}

TEST_CASE("stages: the guide searches wider windows for a long detour and proves a walled goal unreachable") {
  // A 36 m wall between start (2, 3) and goal (2, 9), open only past x = 36: the way round leaves
  // the first search window (start/goal ± 8 m), so the guide must widen it. The goal at (20, 9)
  // is then walled in by keep-out zones, and the goal at (20, 2) by terrain: the guide proves
  // both unreachable (nullopt) without flooding the map.
  std::vector<std::string> picture(12, std::string(40, '.'));
  for (int x = 0; x < 36; ++x) picture[12 - 1 - 6][x] = '#';  // the wall along y = 6
  for (int x = 17; x <= 23; ++x) picture[12 - 1 - 0][x] = picture[12 - 1 - 4][x] = '#';
  for (int y = 0; y <= 4; ++y) picture[12 - 1 - y][17] = picture[12 - 1 - y][23] = '#';
  const terrain::Dem dem = demFromPicture(picture);
  const auto classes = terrain::traversability(dem).classes;
  const CoordinationParams cp;
  const TraversalLattice lattice = makeLattice(dem, classes, cp);
  const auto around = lattice.guidePath({2, 3}, {2, 9});
  REQUIRE(around);
  CHECK((around->back() - Eigen::Vector2d(2, 9)).norm() < 1e-9);
  const double east = std::max_element(around->begin(), around->end(), [](auto& a, auto& b) {
                        return a.x() < b.x();
                      })->x();
  CHECK(east > 36);
  for (std::size_t i = 0; i + 1 < around->size(); ++i)
    CHECK(lattice.model().edgeValid((*around)[i], (*around)[i + 1]));
  // A ring of 16 zones of 1 m round (20, 9), centres 1.5 m from it: covered from 0.6 to 2.4 m.
  std::vector<KeepOutZone> ring;
  for (int j = 0; j < 16; ++j) {
    const double a = j * std::numbers::pi / 8;
    ring.push_back({Eigen::Vector2d(20 + 1.5 * std::cos(a), 9 + 1.5 * std::sin(a)), 1.0});
  }
  bool proven = false;
  CHECK(lattice.guidePath({2, 9}, {20, 9}, {}, &proven));
  CHECK_FALSE(proven);
  CHECK_FALSE(lattice.guidePath({2, 9}, {20, 9}, ring, &proven));
  CHECK(proven);
  CHECK_FALSE(lattice.guidePath({2, 9}, {20, 2}, {}, &proven));  // inside the walled pen
  CHECK(proven);
  CHECK(lattice.guidePath({19, 2}, {21, 2}));  // within the pen
  CHECK_FALSE(lattice.guidePath({19, 2}, {2, 9}, {}, &proven));  // out of it
  CHECK(proven);
  // Zones as the per-cell test reads them: a negative radius as its size, an infinite one
  // everywhere.
  CHECK_FALSE(lattice.guidePath({2, 9}, {20, 9}, {{Eigen::Vector2d(20, 9), -2.0}}));
  CHECK_FALSE(lattice.guidePath({2, 9}, {3, 9}, {{Eigen::Vector2d(30, 1), INFINITY}}));
}

TEST_CASE("stages: the rover simulator drives to a waypoint at 10 Hz") {
  const terrain::Dem dem = demFromPicture(std::vector<std::string>(6, std::string(8, '.')));
  const CoordinationParams cp;
  const RoverSimulator sim(dem, cp.model, cp.controller, cp.slip);
  const Trajectory t = sim.drive({{6, 3}}, {1, 3, 0}, 2.0, 1, nullptr);
  CHECK(t.status == SimStatus::Reached);
  CHECK((endOf(t) - Eigen::Vector2d(6, 3)).norm() <= cp.controller.acceptanceRadius);
  CHECK(t.samples.front().time == doctest::Approx(2.0));
  for (std::size_t i = 1; i < t.samples.size(); ++i)
    CHECK(t.samples[i].time - t.samples[i - 1].time == doctest::Approx(0.1));
  CHECK_THROWS_AS(sim.drive({{6, 3}}, {-3, 3, 0}, 0.0, 1, nullptr), Error);
}

namespace {
// A fake planner whose every path ends 1.2 m north of the goal (Approximate, the goal proved
// cut off), as RRT* does when the zones wall the goal in; goals north of y = 6 it reaches.
class ShortPlanner final : public LegPlanner {
 public:
  PathResult plan(const Eigen::Vector2d& from, double, const Eigen::Vector2d& goal, std::uint64_t,
                  const std::vector<KeepOutZone>&, const CancelToken*) const override {
    PathResult r;
    const bool reaches = goal.y() > 6;
    r.status = reaches ? PathStatus::Exact : PathStatus::Approximate;
    r.goalCutOff = !reaches;
    r.waypoints = {from, reaches ? goal : Eigen::Vector2d(goal + Eigen::Vector2d(0, 1.2))};
    return r;
  }
  bool edgeValid(const Eigen::Vector2d&, const Eigen::Vector2d&) const override { return true; }
  bool canStop(const Eigen::Vector2d&) const override { return true; }
};
}  // namespace

TEST_CASE("stages: timed re-plans end after two short tries with the same keep-out zones") {
  // Rover 0 parks at (10, 7), 2 m north of rover 1's goal (10, 5) — not in its way by the parking
  // rule (1.5 m). Rover 1's plans end short, at (10, 6.2), 0.8 m from rover 0, for good: every
  // try conflicts, and its keep-out zone (3 m round rover 0) would hold the goal, so it is not
  // added. A second short try with the same zones ends the re-plans; without the rule all 20 run.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {10, 9, -M_PI / 2};
  tasks[0].legs.push_back({{10, 9.5}, {}, 0});
  tasks[0].legs.push_back({{10, 7}, {}, 1});
  tasks[1].start = {2, 5, 0};
  tasks[1].legs.push_back({{10, 5}, {}, 2});
  const ShortPlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  p.keepOutRadius = 3;
  const TimedPolicy policy(p);
  REQUIRE(policy.repeatedShortEndsReplans());
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, policy, p, 1);
  REQUIRE(timed.legs.size() == 3);
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK((endOf(timed.trajectories[0]) - Eigen::Vector2d(10, 7)).norm() < 1e-9);
  CHECK(timed.legs[2].status == LegStatus::Skipped);
  CHECK(timed.legs[2].replans == 1);
  TimedPolicy::StopRules without;
  without.repeatedShortEndsReplans = false;
  const CoordinationResult all = coordinateWith(tasks, planner, rover, TimedPolicy(p, without), p, 1);
  REQUIRE(all.legs.size() == 3);
  CHECK(all.legs[2].status == LegStatus::Skipped);
  CHECK(all.legs[2].replans == p.maxReplans);
  CHECK_FALSE(PaperPolicy(p).repeatedShortEndsReplans());
}

TEST_CASE("stages: the coordinator with a fake planner and rover: the policy decides a crossing") {
  const std::vector<RoverTask> tasks = crossingTasks();
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  // Timed: the same try started later clears the crossing; nothing is planned again.
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  REQUIRE(timed.legs.size() == 2);
  CHECK(timed.legs[0].waits == 0);  // the first rover is never disturbed
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK(timed.legs[1].replans == 0);
  CHECK(timed.legs[1].waits == 1);
  CHECK(timed.legs[1].waitTime > 0);
  CHECK(timed.rrtCalls == 2);
  CHECK(timed.conflicts.empty());
  // Paper: every re-plan (the fake ignores keep-out zones) meets rover 0 again, so after
  // max_replans tries the rover waits one wait step and goes.
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  REQUIRE(paper.legs.size() == 2);
  CHECK(paper.legs[1].status == LegStatus::Reached);
  CHECK(paper.legs[1].replans == p.maxReplans);
  CHECK(paper.legs[1].waits == 1);
  CHECK(paper.conflicts.empty());
  for (const CoordinationResult* r : {&timed, &paper}) {
    CHECK(checkSeparation(r->trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
    CHECK((endOf(r->trajectories[0]) - Eigen::Vector2d(10, 5)).norm() < 1e-9);
    CHECK((endOf(r->trajectories[1]) - Eigen::Vector2d(5, 10)).norm() < 1e-9);
  }
  // Without delays, waits or re-plans the leg is skipped and the conflict named.
  CoordinationParams none = p;
  none.maxReplans = 0;
  none.maxWaits = 0;
  const CoordinationResult skipped = coordinateWith(tasks, planner, rover, TimedPolicy(none), none, 1);
  CHECK(skipped.legs[1].status == LegStatus::Skipped);
  CHECK(skipped.legs[1].reason == LegReason::Conflict);
  // Notes count rovers from 1 (rover id 0 is "rover 1") and name the limit (issue 27).
  CHECK(skipped.legs[1].note.find("of rover 1, under safety_distance") != std::string::npos);
}

TEST_CASE("stages: the coordinator reports an invalid and an unreachable goal and goes on") {
  std::vector<RoverTask> tasks(1);
  tasks[0].start = {0, 0, 0};
  tasks[0].legs = {{{3, 0}, {}, 0}, {{3, 3}, {}, 1}, {{0, 3}, {}, 2}};
  StraightLinePlanner planner;
  planner.invalidGoals = {{3, 0}};
  planner.unreachableGoals = {{3, 3}};
  const StraightLineRover rover;
  const CoordinationParams p;
  const TimedPolicy timedRules(p);
  const PaperPolicy paperRules(p);
  for (const ConflictPolicy* policy : {static_cast<const ConflictPolicy*>(&timedRules),
                                       static_cast<const ConflictPolicy*>(&paperRules)}) {
    const CoordinationResult r = coordinateWith(tasks, planner, rover, *policy, p, 1);
    REQUIRE(r.legs.size() == 3);
    CHECK(r.legs[0].status == LegStatus::Skipped);
    CHECK(r.legs[0].reason == LegReason::InvalidGoal);
    CHECK(r.legs[1].status == LegStatus::Short);
    CHECK(r.legs[1].reason == LegReason::NoPath);
    CHECK(r.legs[2].status == LegStatus::Reached);
    CHECK((endOf(r.trajectories[0]) - Eigen::Vector2d(0, 3)).norm() < 1e-9);
  }
  // A policy that never starts a try at once is refused.
  struct Delays final : TimedPolicy {
    Delays(const CoordinationParams& p, std::vector<int> d) : TimedPolicy(p), delays(std::move(d)) {}
    const std::vector<int>& startDelays() const override { return delays; }
    std::vector<int> delays;
  };
  const char* refused = "coordination: a policy starts each try without delay first, then at ascending delays";
  CHECK_THROWS_WITH_AS(coordinateWith(tasks, planner, rover, Delays(p, {5}), p, 1), refused, Error);
  // The coordinator stops at the first delay standing conflicts.
  CHECK_THROWS_WITH_AS(coordinateWith(tasks, planner, rover, Delays(p, {0, 10, 5}), p, 1), refused, Error);
  // Last legs checked for the dwell only need the moves aside at the end.
  struct NoRecovery final : TimedPolicy {
    using TimedPolicy::TimedPolicy;
    bool recovers() const override { return false; }
  };
  CHECK_THROWS_AS(coordinateWith(tasks, planner, rover, NoRecovery(p), p, 1), Error);
  // A departure order given by the caller must hold every rover once.
  planning::Departure twice;
  twice.order = {0, 0};  // one rover, twice
  twice.firstRound = 1;
  const char* notOnce = "coordination: the departure order must hold every rover once";
  CHECK_THROWS_WITH_AS(coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1, nullptr, nullptr, &twice), notOnce, Error);
  planning::Departure missing;
  CHECK_THROWS_WITH_AS(coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1, nullptr, nullptr, &missing), notOnce, Error);
}

TEST_CASE("stages: a rover whose spot will be run over steps aside, then goes on (timed)") {
  // Rover 0 drives east along y = 5 from x = 0 to 20 (at x = 10 after 20 s). Rover 1 comes down
  // from (10, 8) to (10, 5) (there after 6 s; a rover standing at its start is never run over)
  // and must then go west to (0, 5): every try meets rover 0 head-on, and standing still it is
  // run over. Timed: it steps aside off the line, waits there and goes once rover 0 has passed.
  // Paper (no recoveries): the leg is skipped, and the rover only parks out of the way at the end.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {0, 5, 0};
  tasks[0].legs = {{{20, 5}, {}, 0}};
  tasks[1].start = {10, 8, -M_PI / 2};
  tasks[1].legs = {{{10, 5}, {}, 0}, {{0, 5}, {}, 1}};
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  REQUIRE(timed.legs.size() >= 3);
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK(timed.legs[2].status == LegStatus::Reached);
  CHECK(timed.legs[2].pieces == 1);  // the step aside is a move of its own, then the leg
  // It left the line y = 5 before rover 0 came by.
  double off = 0;
  for (const auto& s : timed.trajectories[1].samples)
    if (s.time >= timed.legs[1].endTime) off = std::max(off, std::abs(s.y - 5));
  CHECK(off >= p.safetyDistance);
  CHECK(timed.conflicts.empty());
  CHECK(checkSeparation(timed.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
  CHECK((endOf(timed.trajectories[1]) - Eigen::Vector2d(0, 5)).norm() < 1e-9);
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  CHECK(paper.legs[2].status == LegStatus::Skipped);
  CHECK(paper.conflicts.empty());
}

TEST_CASE("stages: a rover boxed in beside a rover not planned yet steps aside and goes on (timed, issue 25)") {
  // Rover 0 drives east from (0, 0) to (5, 0), stopping 1.05 m from rover 1's start (6.05, 0):
  // rover 1 is planned after it, so the traffic table holds it standing there all along. Standing
  // is clear, but rover 0's next leg, to (8, 2.5), heads past rover 1 within 0.7 m and comes
  // closer than the safety distance in its first second, at every delay (rover 1 never moves in
  // the table) and every re-plan (the fake planner draws the same line). Before issue 25's fix
  // the leg was skipped, and so was every later leg from the same spot; now the rover steps
  // aside (2 m back along its track, from where the line to (8, 2.5) clears rover 1) and goes on.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {0, 0, 0};
  tasks[0].legs = {{{5, 0}, {}, 0}, {{8, 2.5}, {}, 1}};
  tasks[1].start = {6.05, 0, -M_PI / 2};
  tasks[1].legs = {{{6.05, -4}, {}, 2}};
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  std::vector<const LegRecord*> legs0;
  for (const LegRecord& l : timed.legs)
    if (l.rover == 0 && l.leg < 2) legs0.push_back(&l);
  REQUIRE(legs0.size() == 2);
  CHECK(legs0[0]->status == LegStatus::Reached);
  CHECK(legs0[1]->status == LegStatus::Reached);
  CHECK(legs0[1]->note.empty());
  CHECK((endOf(timed.trajectories[0]) - Eigen::Vector2d(8, 2.5)).norm() < 0.5);
  CHECK(timed.conflicts.empty());
  CHECK(checkSeparation(timed.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
  // Paper (no recoveries) still skips it, for rover 1 within the safety distance.
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  for (const LegRecord& l : paper.legs)
    if (l.rover == 0 && l.leg == 1) CHECK(l.status == LegStatus::Skipped);
  CHECK(paper.conflicts.empty());
}

TEST_CASE("stages: a last leg whose goal is passed long after the dwell is reached, then parks aside (timed)") {
  // Rover 1 drives north from (10, 0) to (10, 5), its only leg: there after 10 s. Rover 0 drives
  // east along y = 5 from x = -60 and passes (10, 5) after 140 s. Paper: the last leg is checked
  // standing at its goal for good, so every try and re-plan meets rover 0 and the leg is skipped.
  // Timed: the leg is checked for the dwell like any other and reached at once; the rover then
  // parks out of rover 0's way before it comes.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {-60, 5, 0};
  tasks[0].legs = {{{20, 5}, {}, 0}};
  tasks[1].start = {10, 0, M_PI / 2};
  tasks[1].legs = {{{10, 5}, {}, 0}};
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  REQUIRE(timed.legs.size() == 3);  // rover 0's leg, rover 1's leg, rover 1 parking aside
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK(timed.legs[1].replans == 0);
  CHECK(timed.legs[1].endTime == doctest::Approx(10.0));
  CHECK(timed.legs[2].note == "parked out of the way");
  CHECK(timed.legs[2].startTime < 140.0 - p.safetyDistance / 0.5);
  CHECK(timed.rrtCalls == 2);
  CHECK(timed.conflicts.empty());
  CHECK(checkSeparation(timed.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  CHECK(paper.legs[1].status == LegStatus::Skipped);
  CHECK(paper.legs[1].replans == p.maxReplans);
  CHECK(paper.conflicts.empty());
}

// The straight-line planner, but the rover may stop and turn only at the given points.
class StopsOnlyAt final : public LegPlanner {
 public:
  explicit StopsOnlyAt(std::vector<Eigen::Vector2d> at) : at_(std::move(at)) {}
  PathResult plan(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal, std::uint64_t seed,
                  const std::vector<KeepOutZone>& keepOut, const CancelToken* cancel) const override {
    return line_.plan(from, heading, goal, seed, keepOut, cancel);
  }
  bool edgeValid(const Eigen::Vector2d&, const Eigen::Vector2d&) const override { return true; }
  bool canStop(const Eigen::Vector2d& p) const override {
    return std::any_of(at_.begin(), at_.end(), [&](const auto& q) { return (p - q).norm() < 1e-9; });
  }

 private:
  StraightLinePlanner line_;
  std::vector<Eigen::Vector2d> at_;
};

TEST_CASE("stages: a rover with no spot to park aside stops where it may stand for good (issue 25)") {
  // Rover 0 drives east along y = 5 from x = -60 and passes (10, 5) after 140 s. Rover 1 drives
  // north from (10, -5.5) to (10, -0.5), then to (10, 5), there after 21 s: each leg is checked
  // for the dwell and reached. Standing at (10, 5) it would be run over at 140 s, and it can stop
  // nowhere but at its two goals (the first off park()'s rings and its spots back along the
  // trajectory), so park() finds no spot (as at a map edge, issue 25's
  // Gale run: rovers 2 and 3 ran over a finished rover 4 four times). It stops at the end of its
  // first leg instead, which no planned rover comes near; the second leg is undone.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {-60, 5, 0};
  tasks[0].legs = {{{20, 5}, {}, 0}};
  tasks[1].start = {10, -5.5, M_PI / 2};
  tasks[1].legs = {{{10, -0.5}, {}, 0}, {{10, 5}, {}, 1}};
  const StopsOnlyAt planner({{10, -0.5}, {10, 5}, {20, 5}});
  const StraightLineRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  CHECK(timed.conflicts.empty());
  CHECK(checkSeparation(timed.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
  CHECK((endOf(timed.trajectories[1]) - Eigen::Vector2d(10, -0.5)).norm() < 1e-9);
  CHECK(timed.trajectories[1].samples.back().time == doctest::Approx(10.0));
  REQUIRE(timed.legs.size() == 3);  // no move aside is left
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK(timed.legs[2].status == LegStatus::Skipped);
  CHECK(timed.legs[2].reason == LegReason::Conflict);
  CHECK(timed.legs[2].endTime == doctest::Approx(10.0));
  CHECK(timed.legs[2].note.find("undone: standing at its end") == 0);
  CHECK(timed.legs[2].note.find("of rover 1, under safety_distance") != std::string::npos);
  CHECK(timed.paths[1].size() == 2);  // its start and the first goal
  // Paper checks a last leg standing at its goal for good: skipped there already.
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  CHECK(paper.conflicts.empty());
  CHECK((endOf(paper.trajectories[1]) - Eigen::Vector2d(10, -0.5)).norm() < 1e-9);
}

TEST_CASE("stages: a rover with no spot to park aside moves aside from an earlier stop when it can (issue 25)") {
  // As above, with three legs: (10, -0.5), (10, 4.5), (10, 5), and one more spot it may stop at,
  // (10, 2): 2.5 m south of the second goal (on the ring park() searches round it) but on no ring
  // or spot back along the trajectory round the last goal. park() finds nothing at (10, 5); from
  // the second goal the rover reaches (10, 2), clear for good: only the last leg is undone.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {-60, 5, 0};
  tasks[0].legs = {{{27, 5}, {}, 0}};
  tasks[1].start = {10, -5.5, M_PI / 2};
  tasks[1].legs = {{{10, -0.5}, {}, 0}, {{10, 4.5}, {}, 1}, {{10, 5}, {}, 2}};
  const StopsOnlyAt planner({{10, -0.5}, {10, 4.5}, {10, 5}, {10, 2}, {27, 5}});
  const StraightLineRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  CHECK(timed.conflicts.empty());
  CHECK(checkSeparation(timed.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance);
  CHECK((endOf(timed.trajectories[1]) - Eigen::Vector2d(10, 2)).norm() < 1e-6);
  REQUIRE(timed.legs.size() == 5);  // rover 0's leg, rover 1's three legs and its move aside
  CHECK(timed.legs[1].status == LegStatus::Reached);
  CHECK(timed.legs[2].status == LegStatus::Reached);
  CHECK(timed.legs[3].status == LegStatus::Skipped);
  CHECK(timed.legs[3].reason == LegReason::Conflict);
  CHECK(timed.legs[3].note.find("; it moves aside from (10.0, 4.5) at t = 20.0 s") != std::string::npos);
  CHECK(timed.legs[4].note == "parked out of the way");
  CHECK(timed.legs[4].startTime == doctest::Approx(timed.legs[2].endTime + 0.1));  // from the second goal
}

TEST_CASE("stages: timed re-plans end after three tries that meet a rover standing by the goal") {
  // Rover 1 drives north from (10, 0) to (10, 5): there after 10 s, then dwells. Rover 0 comes
  // west along y = 5.8 and paces between x = 9.5 and 10.5 from 18.8 s for 80 s, within 1 m of
  // rover 1's goal. Every try meets it while rover 1 stands at the goal (or drives its last metre,
  // started later), and no keep-out zone can be placed there: it would wall the goal in. Timed:
  // the re-plans end after three such tries, and the rover waits (past max_waits × wait_step)
  // until rover 0 has done pacing and gone, then goes; paper: all 20 re-plans.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {20, 5.8, M_PI};
  tasks[0].legs.push_back({{10.5, 5.8}, {}, 0});
  for (int j = 0; j < 40; ++j) tasks[0].legs.push_back({{j % 2 == 0 ? 9.5 : 10.5, 5.8}, {}, j + 1});
  tasks[1].start = {10, 0, M_PI / 2};
  tasks[1].legs = {{{10, 5}, {}, 0}};
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  const auto leg1 = [](const CoordinationResult& r) {
    return *std::find_if(r.legs.begin(), r.legs.end(), [](const LegRecord& l) { return l.rover == 1; });
  };
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  CHECK(leg1(timed).replans == TimedPolicy(p).unzonedConflictsEndReplans() - 1);
  CHECK(leg1(timed).status == LegStatus::Reached);
  CHECK(leg1(timed).waits == 1);
  CHECK(leg1(timed).waitTime > p.maxWaits * p.waitStep);
  CHECK(leg1(timed).endTime > 18.8 + 80);  // after the pacing
  CHECK(timed.conflicts.empty());
  // max_waits = 0: no waiting at all, the leg is skipped.
  CoordinationParams noWaits = p;
  noWaits.maxWaits = 0;
  const CoordinationResult impatient = coordinateWith(tasks, planner, rover, TimedPolicy(noWaits), noWaits, 1);
  CHECK(leg1(impatient).status == LegStatus::Skipped);
  CHECK(leg1(impatient).reason == LegReason::Conflict);
  TimedPolicy::StopRules untiring;
  untiring.unzonedConflictsEndReplans = 0;
  CHECK(leg1(coordinateWith(tasks, planner, rover, TimedPolicy(p, untiring), p, 1)).replans == p.maxReplans);
  CHECK(leg1(coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1)).replans == p.maxReplans);
  // Rover 0 paces across rover 1's way 1.2 m short of its goal instead (a zone there would still
  // wall the goal in): met on the way, which another path may dodge, so every re-plan is tried.
  tasks[0].start = {12, 3.8, M_PI};
  tasks[0].legs.clear();
  for (int j = 0; j < 50; ++j) tasks[0].legs.push_back({{j % 2 == 0 ? 9.5 : 10.5, 3.8}, {}, j});
  const CoordinationResult onTheWay = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  CHECK(leg1(onTheWay).replans == p.maxReplans);
  CHECK(leg1(onTheWay).status == LegStatus::Reached);  // waited for the pacing to end, as above
  CHECK(onTheWay.conflicts.empty());
}

namespace {
// A fake planner whose plans keep-out zones cut off: straight to the goal, or, when a zone
// reaches the straight line, a 0.2 m stub towards it, cut off from the goal.
class ZonedShortPlanner final : public LegPlanner {
 public:
  PathResult plan(const Eigen::Vector2d& from, double, const Eigen::Vector2d& goal, std::uint64_t,
                  const std::vector<KeepOutZone>& keepOut, const CancelToken*) const override {
    const bool cut = std::any_of(keepOut.begin(), keepOut.end(), [&](const KeepOutZone& z) {
      const double s = std::clamp((z.centre - from).dot(goal - from) / (goal - from).squaredNorm(), 0.0, 1.0);
      return (from + s * (goal - from) - z.centre).norm() < z.radius;
    });
    PathResult r;
    r.status = cut ? PathStatus::Approximate : PathStatus::Exact;
    r.goalCutOff = cut;
    r.waypoints = {from, cut ? Eigen::Vector2d(from + 0.2 * (goal - from).normalized()) : goal};
    return r;
  }
  bool edgeValid(const Eigen::Vector2d&, const Eigen::Vector2d&) const override { return true; }
  bool canStop(const Eigen::Vector2d&) const override { return true; }
};
}  // namespace

TEST_CASE("stages: timed, a plan the earlier tries' zones cut off is not driven when a try reached the goal") {
  // Rover 0 paces across rover 1's way 1.2 m short of its goal for about 100 s; rover 1's first
  // try reaches the goal but meets it, and the keep-out zone round rover 0 (1 m) cuts every later
  // plan off 0.2 m on. Driven, such a stub ends the piece without progress and the leg short of
  // a goal the rover reaches once rover 0 has gone (issue 25, the Kepler site). Timed: the stubs
  // are not driven; the re-plans end (two short tries with the same zones) and the first try
  // waits for the pacing to end.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {12, 3.8, M_PI};
  for (int j = 0; j < 50; ++j) tasks[0].legs.push_back({{j % 2 == 0 ? 9.5 : 10.5, 3.8}, {}, j});
  tasks[1].start = {10, 0, M_PI / 2};
  tasks[1].legs = {{{10, 5}, {}, 0}};
  const ZonedShortPlanner planner;
  const StraightLineRover rover;
  CoordinationParams p;
  p.keepOutRadius = 1.0;  // a zone round rover 0 that does not hold rover 1's goal
  const CoordinationResult r = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  const auto leg = std::find_if(r.legs.begin(), r.legs.end(), [](const LegRecord& l) { return l.rover == 1; });
  REQUIRE(leg != r.legs.end());
  CHECK(leg->status == LegStatus::Reached);
  CHECK(leg->pieces == 1);  // the first try, later; no stub
  CHECK(leg->replans == 2);
  CHECK(leg->waitTime > p.maxWaits * p.waitStep);
  CHECK(r.conflicts.empty());
  CHECK((endOf(r.trajectories[1]) - Eigen::Vector2d(10, 5)).norm() <= p.controller.acceptanceRadius + 1e-9);
}

TEST_CASE("stages: timed, a goal the standing rovers' zones alone cut off is planned for without them") {
  // Rover 1, planned after rover 0, stands 1.1 m beside rover 0's straight way: farther than the
  // safety distance, inside its keep-out zone (safety + 0.25 m), which cuts every plan off. The
  // piece plans on without the standing zones and rover 0 drives past, 1.1 m from rover 1.
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {0, 0, 0};
  tasks[0].legs.push_back({{10, 0}, {}, 0});
  tasks[1].start = {5, 1.1, 0};
  const ZonedShortPlanner planner;
  const StraightLineRover rover;
  const CoordinationParams p;
  const TimedPolicy policy(p);
  REQUIRE(policy.standingKeepOut() > 1.1);
  const CoordinationResult r = coordinateWith(tasks, planner, rover, policy, p, 1);
  REQUIRE(r.legs.size() == 1);
  CHECK(r.legs[0].status == LegStatus::Reached);
  CHECK(r.legs[0].pieces == 1);
  CHECK(r.legs[0].replans == 1);  // the plan with the standing zone, then the one without
  CHECK(r.conflicts.empty());
  CHECK((endOf(r.trajectories[0]) - Eigen::Vector2d(10, 0)).norm() < 1e-9);
}

namespace {
// The fake rover on a strip x < 1 steeper than the limit across: turning in place there by more
// than 45° tilts it to 20°; driving is fine everywhere.
class StripRover final : public LegSimulator {
 public:
  Trajectory drive(const std::vector<Eigen::Vector2d>& waypoints, const Pose& start,
                   double startTime, std::uint64_t seed, const CancelToken* cancel) const override {
    Trajectory t = straight_.drive(waypoints, start, startTime, seed, cancel);
    const Eigen::Vector2d to = waypoints.front() - Eigen::Vector2d(start.x, start.y);
    const double turn = std::abs(std::remainder(std::atan2(to.y(), to.x()) - start.heading, 2 * M_PI));
    if (start.x < 1 && turn > M_PI / 4 && t.samples.size() > 1) t.samples[1].pitch = 20 * M_PI / 180;
    return t;
  }

 private:
  StraightLineRover straight_;
};
}  // namespace

TEST_CASE("stages: a rover that tilts turning where it stands drives straight out first (timed)") {
  // The rover stands on the strip facing east; its goal is behind it. Timed: it drives out east
  // off the strip, turns there and reaches the goal. Paper: every try tilts, the leg ends short.
  std::vector<RoverTask> tasks(1);
  tasks[0].start = {0.5, 0, 0};
  tasks[0].legs = {{{-3, 0}, {}, 0}};
  const StraightLinePlanner planner;
  const StripRover rover;
  CoordinationParams p;
  const CoordinationResult timed = coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1);
  REQUIRE(timed.legs.size() == 1);
  CHECK(timed.legs[0].status == LegStatus::Reached);
  CHECK(timed.legs[0].pieces == 1);  // the drive out is a move of its own
  double east = 0;
  for (const auto& s : timed.trajectories[0].samples) east = std::max(east, s.x);
  CHECK(east >= 1.0);  // it left the strip before turning
  for (const auto& s : timed.trajectories[0].samples) CHECK(std::abs(s.pitch) < p.attitudeCheck);
  const CoordinationResult paper = coordinateWith(tasks, planner, rover, PaperPolicy(p), p, 1);
  CHECK(paper.legs[0].status == LegStatus::Short);
  CHECK(paper.legs[0].reason == LegReason::Steep);
  // The note names the check that refused the tries, its value and the tilt reached (issue 27:
  // it said "the attitude limit" while the operator's attitude_limit was 45°).
  CHECK(paper.legs[0].note == "every try tilts past attitude_check 15.0° (the least tilted try reached 20.0° pitch)");
}

namespace {
// A fake planner whose path depends on the seed alone (and throws for one goal). Its 200 µs pause
// stands for a planner's work (the behaviour under test is workers and the asking thread
// overlapping); the results checked do not depend on it.
class SeededPlanner final : public LegPlanner {
 public:
  PathResult plan(const Eigen::Vector2d& from, double, const Eigen::Vector2d& goal, std::uint64_t seed,
                  const std::vector<KeepOutZone>& keepOut, const CancelToken*) const override {
    if (goal.x() < 0) throw Error(ErrorCode::InvalidInput, "goal", "a goal off the map");
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    PathResult r;
    r.status = PathStatus::Exact;
    r.waypoints = {from, Eigen::Vector2d(static_cast<double>(seed % 97), static_cast<double>(keepOut.size())),
                   goal};
    return r;
  }
  bool edgeValid(const Eigen::Vector2d&, const Eigen::Vector2d&) const override { return true; }
  bool canStop(const Eigen::Vector2d&) const override { return true; }
};
}  // namespace

TEST_CASE("stages: legs planned ahead on workers are the plans made alone, asked for in any order") {
  std::vector<PlanAhead::Job> jobs;
  for (int j = 0; j < 60; ++j)
    jobs.push_back({{0, 0}, 0.0, {static_cast<double>(j + 1), 1}, 1000u + static_cast<unsigned>(j), j % 7 != 3, {}});
  const SeededPlanner planner;
  std::vector<std::vector<Eigen::Vector2d>> alone;
  for (const auto& job : jobs) alone.push_back(planner.plan(job.start, job.heading, job.goal, job.seed, {}, nullptr).waypoints);
  for (unsigned workers : {0u, 1u, 3u}) {
    CAPTURE(workers);
    PlanAhead ahead(planner, jobs, workers, nullptr);
    // Asked for out of order, some twice.
    for (std::size_t j : {5u, 0u, 59u, 5u, 17u, 3u}) {
      const PathResult* r = ahead.get(j);
      if (!jobs[j].planned) {
        CHECK(r == nullptr);
        continue;
      }
      REQUIRE(r != nullptr);
      CHECK(r->waypoints == alone[j]);
    }
    CHECK(ahead.finish() == 51);  // 60 jobs, 9 not planned: the same count whatever the threads
    for (std::size_t j = 0; j < jobs.size(); ++j)
      if (jobs[j].planned) CHECK(ahead.get(j)->waypoints == alone[j]);
  }
  // A planning error reaches the one who asks for that plan, and finish().
  jobs[11].goal = {-1, 0};
  PlanAhead failing(planner, jobs, 1, nullptr);
  CHECK_THROWS_AS(failing.get(11), Error);
  CHECK_THROWS_AS(failing.finish(), Error);
  // Destroyed before finish(): the workers stop without planning everything.
  { PlanAhead abandoned(planner, jobs, 2, nullptr); }
}

TEST_CASE("stages: a speculated re-plan is the plan made alone, used only for its own request") {
  const SeededPlanner planner;
  auto request = [](std::uint64_t seed, std::size_t zones) {
    PlanAhead::Request r{{1, 2}, 0.5, {9, 3}, seed, {}};
    for (std::size_t z = 0; z < zones; ++z) r.keepOut.push_back({{5, static_cast<double>(z)}, 0.5});
    return r;
  };
  auto alone = [&](const PlanAhead::Request& r) {
    return planner.plan(r.from, r.heading, r.goal, r.seed, r.keepOut, nullptr).waypoints;
  };
  for (unsigned workers : {0u, 1u, 3u}) {
    CAPTURE(workers);
    std::vector<PlanAhead::Job> jobs;
    for (int j = 0; j < 8; ++j) jobs.push_back({{0, 0}, 0.0, {static_cast<double>(j + 1), 1}, 7u + j, true, {}});
    PlanAhead ahead(planner, jobs, workers, nullptr);
    // A run of tries with the same zones, each speculating the next, as the coordinator does.
    for (std::uint64_t seed = 100; seed < 110; ++seed) {
      ahead.speculate(request(seed + 1, 2));
      CHECK(ahead.plan(request(seed, 2)).waypoints == alone(request(seed, 2)));
    }
    // The zones changed after all: the speculation is not used for the new request.
    ahead.speculate(request(200, 2));
    CHECK(ahead.plan(request(200, 3)).waypoints == alone(request(200, 3)));
    CHECK(ahead.plan(request(200, 2)).waypoints == alone(request(200, 2)));
    // Many unused speculations stay bounded and do not disturb the leg jobs.
    for (std::uint64_t seed = 300; seed < 340; ++seed) ahead.speculate(request(seed, 1));
    CHECK(ahead.get(4)->waypoints == planner.plan({0, 0}, 0, {5, 1}, 11u, {}, nullptr).waypoints);
    CHECK(ahead.finish() == 8);
  }
  // A speculated plan's error reaches the one who asks for it.
  PlanAhead failing(planner, {}, 1, nullptr);
  PlanAhead::Request off = request(5, 0);
  off.goal = {-1, 0};
  failing.speculate(off);
  CHECK_THROWS_AS(failing.plan(off), Error);
  CHECK(failing.finish() == 0);
}

TEST_CASE("stages: a 3×3 block of rovers at the safety distance all leave without a collision") {
  // Rovers on a 1 m lattice (exactly the safety distance), row-major; each outer one drives 10 m
  // straight out, the centre (rovers[4]) 7 m west, behind rovers[3]. Every rover stands at its
  // start until it is planned, so the centre, boxed in by its eight neighbours, is planned after
  // them (planned fifth, with rovers 5 to 8 standing for good, it could never leave) (issue 25).
  std::vector<RoverTask> tasks(9);
  for (int k = 0; k < 9; ++k) {
    const Eigen::Vector2d at(10 + k % 3, 10 + k / 3);
    const Eigen::Vector2d out = at - Eigen::Vector2d(11, 11);
    const Eigen::Vector2d goal = k == 4 ? Eigen::Vector2d(4, 11) : Eigen::Vector2d(at + 10 * out.normalized());
    tasks[k].start = {at.x(), at.y(), 0};
    tasks[k].legs.push_back({goal, {}, k});
  }
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  const CoordinationParams p;
  const TimedPolicy timed(p);
  const PaperPolicy paper(p);
  for (const ConflictPolicy* policy : {static_cast<const ConflictPolicy*>(&timed),
                                       static_cast<const ConflictPolicy*>(&paper)}) {
    CAPTURE(policy->name());
    const CoordinationResult r = coordinateWith(tasks, planner, rover, *policy, p, 1);
    CHECK(r.conflicts.empty());
    CHECK(checkSeparation(r.trajectories, p.safetyDistance).minimumDistance >= p.safetyDistance - 1e-9);
    REQUIRE(r.legs.size() == 9);
    for (const LegRecord& leg : r.legs) {
      CAPTURE(leg.rover);
      CHECK(leg.status == LegStatus::Reached);
    }
  }
}

TEST_CASE("stages: rovers closer than the safety distance are refused naming the rover") {
  std::vector<RoverTask> tasks(3);
  tasks[0].start = {0, 0, 0};
  tasks[1].start = {10, 0, 0};
  tasks[2].start = {10.5, 0, 0};  // 0.5 m from rovers[1]: neither can stand there safely
  for (auto& t : tasks) t.legs.push_back({{t.start.x, 20}, {}, 0});
  const StraightLinePlanner planner;
  const StraightLineRover rover;
  const CoordinationParams p;
  CHECK_THROWS_WITH_AS(coordinateWith(tasks, planner, rover, TimedPolicy(p), p, 1),
                       "rovers[1]: start is boxed in: no way out past the other rovers' starts keeping "
                       "the safety distance (+ 0.5 m)",
                       Error);
}

// Issue 27: every incident note states the limit hit (parameter name and value) and the value
// reached; its cause groups it. An exceedance episode of three samples over a 10° limit, the
// worst a 14° pitch, closed by a sample back under the limit.
TEST_CASE("team incidents: notes name the limit and the value reached; causes group them") {
  const double deg = std::numbers::pi / 180;
  ExceedanceScan scan(1, 10 * deg);
  auto sample = [&](double t, double roll, double pitch) {
    TrajectorySample s;
    s.time = t;
    s.x = t;
    s.y = 2 * t;
    s.roll = roll * deg;
    s.pitch = pitch * deg;
    return s;
  };
  CHECK_FALSE(scan.add(sample(0, 3, 4)));
  CHECK_FALSE(scan.add(sample(0.1, 11, 2)));
  CHECK_FALSE(scan.add(sample(0.2, 5, -14)));
  CHECK_FALSE(scan.add(sample(0.3, 12, 1)));
  const auto e = scan.add(sample(0.4, 1, 1));
  REQUIRE(e);
  CHECK(e->kind == IncidentKind::Exceedance);
  CHECK(e->rover == 1);
  CHECK(e->time == doctest::Approx(0.1));
  CHECK(e->position.x() == doctest::Approx(0.1));
  CHECK(e->value == doctest::Approx(14));
  CHECK(e->note == "|pitch| reached 14.00° over exceedance_limit 10.0° for 3 samples");
  CHECK(e->cause == "exceedance_limit");
  CHECK_FALSE(scan.finish());  // closed already
  CHECK_FALSE(scan.add(sample(0.5, -10.5, 0)));
  const auto open = scan.finish();  // still open at the end of the trajectory
  REQUIRE(open);
  CHECK(open->note == "|roll| reached 10.50° over exceedance_limit 10.0° for 1 samples");

  Conflict c;
  c.rover = 2;
  c.other = 0;
  c.distance = 0.62;
  c.duration = 1.5;
  const Incident col = collisionIncident(c, 1.0);
  CHECK(col.note == "rovers 1 and 3 came within 0.62 m, under safety_distance 1.00 m, for 1.5 s");
  CHECK(col.cause == "safety_distance");
  CHECK(col.other == 0);

  const Incident slot = noSlotIncident(0, 7, {5, 5}, 5.0);
  CHECK(slot.note == "target 7: no valid ground for the rover's slot within half footprint_m (2.50 m of 5.00 m)");
  CHECK(slot.cause == "no_ground");
  CHECK(noSlotIncident(0, 7, {5, 5}, 5.0, true).note ==
        "target 7: no valid ground for the rover's slot within half footprint_m (2.50 m of 5.00 m), nor any "
        "left free in the target's search cell");

  LegRecord leg;
  leg.rover = 1;
  leg.target = 4;
  leg.status = LegStatus::Short;
  leg.reason = LegReason::Steep;
  leg.endTime = 12.5;
  leg.note = "every try tilts past attitude_check 15.0° (the least tilted try reached 17.3° pitch)";
  const Incident s = legIncident(leg, {3, 4});
  CHECK(s.kind == IncidentKind::Short);
  CHECK(s.cause == "steep");
  CHECK(s.note == "target 4: " + leg.note);
  CHECK(s.time == 12.5);
}

TEST_CASE("stages: laneTurn gives every rover of a formation its own lane along a leg of any heading") {
  // The lattice turned by atan(1/m) against the leg: point (i, j) lies (i + m·j) lattice steps
  // / √(m² + 1) to the side, distinct for every point; distances between slots are kept.
  for (int n : {2, 4, 5, 9, 16}) {
    const std::vector<Eigen::Vector2d> slots = goalSlots(n, 5.0, 1.5);
    const int m = static_cast<int>(std::ceil(std::sqrt(n) - 1e-9));
    // The lattice step after goalSlots' spread, and the lane step it gives.
    const double scale = slots[1].norm() / formationSlots(n, 5.0)[1].norm();
    const double step = 5.0 / m * scale / std::sqrt(m * m + 1.0);
    for (int k = 0; k < 16; ++k) {
      CAPTURE(n);
      CAPTURE(k);
      const double h = k * std::numbers::pi / 8;
      const std::vector<Eigen::Vector2d> turned = turnedSlots(slots, laneTurn(n, h));
      const Eigen::Vector2d side(-std::sin(h), std::cos(h));
      std::vector<double> lanes;
      for (const auto& s : turned) lanes.push_back(s.dot(side));
      std::sort(lanes.begin(), lanes.end());
      for (std::size_t i = 1; i < lanes.size(); ++i) CHECK(lanes[i] - lanes[i - 1] >= step - 1e-9);
      for (std::size_t a = 0; a < slots.size(); ++a)
        for (std::size_t b = a + 1; b < slots.size(); ++b)
          CHECK(std::abs((turned[a] - turned[b]).norm() - (slots[a] - slots[b]).norm()) < 1e-9);
    }
  }
  CHECK(laneTurn(1, 0.3) == 0.0);
  // Five rovers: east and north-east legs turn the slots by 18.4° and 26.6°, lanes 1.05 m apart.
  CHECK(laneTurn(5, 0.0) == doctest::Approx(std::atan(1.0 / 3)));
  CHECK(laneTurn(5, std::numbers::pi / 4) == doctest::Approx(std::numbers::pi / 4 - std::atan(1.0 / 3)));
}

TEST_CASE("stages: on the orienteering route the formation's five rovers drive five distinct lanes on every heading") {
  // A 60 m flat map, a route of two targets 5 m (7.07 m on diagonals) apart on each of the eight
  // headings round an octagon. On the leg between the two targets of a pair, every rover's goal
  // at both ends lies the same distance to the side of the leg (it drives its own lane), and the
  // five lanes are at least the sensing diameter (1 m) apart: the swept strip is the whole
  // footprint. LHC_GW_CONV keeps paper 001's square slots: three lanes on each such leg.
  const terrain::Dem dem = demFromPicture(std::vector<std::string>(60, std::string(60, '.')));
  const auto classes = terrain::traversability(dem).classes;
  const std::vector<Eigen::Vector2d> centres{{25, 15}, {30, 15}, {35, 20}, {40, 25}, {40, 30}, {40, 35},
                                             {35, 40}, {30, 45}, {25, 45}, {20, 45}, {15, 40}, {10, 35},
                                             {10, 30}, {10, 25}, {15, 20}, {20, 15}};
  const std::vector<Pose> starts{{15, 15, 0}, {15, 12.5, 0}, {15, 17.5, 0}, {12.5, 15, 0}, {17.5, 15, 0}};  // centroid (15, 15): due west
  const auto lanesOn = [&](const TeamMissionParams& p) {
    const std::vector<RoverTask> tasks = SlotTasks(dem, classes, p, nullptr).build(starts, routeThrough(centres), nullptr);
    std::vector<std::vector<double>> out;  // per pair, the lanes of the five rovers (nan: moved)
    for (std::size_t t = 1; t < centres.size(); t += 2) {
      const Eigen::Vector2d d = (centres[t] - centres[t - 1]).normalized(), side(-d.y(), d.x());
      std::vector<double> lanes;
      for (const RoverTask& task : tasks) {
        REQUIRE(task.legs.size() == centres.size());
        const double from = (task.legs[t - 1].goal - centres[t - 1]).dot(side);
        const double to = (task.legs[t].goal - centres[t]).dot(side);
        lanes.push_back(std::abs(from - to) < 1e-9 ? to : std::nan(""));
      }
      std::sort(lanes.begin(), lanes.end());
      out.push_back(lanes);
    }
    return out;
  };
  TeamMissionParams ours;
  ours.routeMethod = RouteMethod::Orienteering;
  const auto lanes = lanesOn(ours);
  REQUIRE(lanes.size() == 8);
  for (std::size_t leg = 0; leg < lanes.size(); ++leg) {
    CAPTURE(leg);
    for (std::size_t i = 1; i < 5; ++i) CHECK(lanes[leg][i] - lanes[leg][i - 1] >= 1.0);
    CHECK(lanes[leg][4] - lanes[leg][0] > 4.0);  // a 5 m strip (plus each rover's 1 m disc)
  }
  for (const auto& legLanes : lanesOn(TeamMissionParams{})) {
    int distinct = 1;
    for (std::size_t i = 1; i < 5; ++i) distinct += legLanes[i] - legLanes[i - 1] > 0.5 ? 1 : 0;
    CHECK(distinct == 3);
  }
  // The paper mode keeps paper 001's slots on the orienteering route too.
  TeamMissionParams paper = ours;
  paper.coordination.mode = CoordinationMode::Paper;
  for (const auto& legLanes : lanesOn(paper)) {
    int distinct = 1;
    for (std::size_t i = 1; i < 5; ++i) distinct += legLanes[i] - legLanes[i - 1] > 0.5 ? 1 : 0;
    CHECK(distinct == 3);
  }
}
