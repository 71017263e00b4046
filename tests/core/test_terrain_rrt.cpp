#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/team/grid_neighbors.hpp"
#include "core/team/terrain_rrt.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;
using terrain::Dem;
using terrain::TerrainClass;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

using rover::test::demFrom;

Dem flatDem(int rows, int cols, double cell) {
  return demFrom(rows, cols, cell, [](double, double) { return 0.0; });
}

Raster<std::uint8_t> allClass(const Dem& d, TerrainClass c) {
  return Raster<std::uint8_t>(d.geometry(), static_cast<std::uint8_t>(c));
}

void setCell(Raster<std::uint8_t>& classes, const Eigen::Vector2d& p, TerrainClass c) {
  auto cell = localToCell(classes.geometry, p);
  REQUIRE(cell);
  classes(cell->row, cell->col) = static_cast<std::uint8_t>(c);
}

SearchBounds wholeMap(const Dem& d) {
  return {{0, 0}, {d.geometry().widthMetres(), d.geometry().heightMetres()}};
}

double polylineLength(const std::vector<Eigen::Vector2d>& p) {
  double s = 0;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) s += (p[i + 1] - p[i]).norm();
  return s;
}

std::string errorField(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.field();
  }
  return "<no error>";
}
}  // namespace

TEST_CASE("rrt: parameters are validated, the error names the field") {
  Dem d = flatDem(8, 8, 1.0);
  auto cls = allClass(d, TerrainClass::Traversable);
  auto plan = [&](RrtParams p, TerrainCostWeights w = {}) {
    planPath(d, cls, {1, 1}, 0, {6, 6}, p, w);
  };
  RrtParams p;
  p.range = 0;
  CHECK_THROWS_WITH_AS(plan(p), "range: must be a finite number > 0", Error);
  p = {};
  p.maxVertices = 1;
  CHECK(errorField([&] { plan(p); }) == "max_vertices");
  p = {};
  p.clearance = -1;
  CHECK(errorField([&] { plan(p); }) == "clearance");
  p = {};
  p.attitudeLimit = 2.0;
  CHECK(errorField([&] { plan(p); }) == "attitude_limit");
  p = {};
  p.edgeResolution = std::nan("");
  CHECK(errorField([&] { plan(p); }) == "edge_resolution");
  p = {};
  p.goalBias = 1.5;
  CHECK(errorField([&] { plan(p); }) == "goal_bias");
  TerrainCostWeights w;
  w.nPsi = 0;
  CHECK(errorField([&] { plan({}, w); }) == "n_psi");
  w = {};
  w.wTheta = -0.1;
  CHECK(errorField([&] { plan({}, w); }) == "w_theta");
  CHECK(errorField([&] { planPath(d, cls, {1, 1}, std::nan(""), {6, 6}); }) == "start_heading");
  // Classes on another grid than the DEM: bad input.
  Raster<std::uint8_t> small(GridGeometry{4, 4, 1.0, 1.0}, 0);
  CHECK(errorField([&] { planPath(d, small, {1, 1}, 0, {6, 6}); }) == "classes");
}

TEST_CASE("rrt: search bounds are the box of start and goal plus the clearance, clipped") {
  GridGeometry g{40, 60, 0.25, 0.25};  // 15 m × 10 m
  SearchBounds b = searchBounds(g, {3, 9}, {7, 4}, 2.0);
  CHECK(b.min.x() == 1.0);
  CHECK(b.min.y() == 2.0);
  CHECK(b.max.x() == 9.0);
  CHECK(b.max.y() == 10.0);  // 11 clipped to the map's 10 m
  CHECK(headingChange(0, std::numbers::pi / 2) == doctest::Approx(std::numbers::pi / 2));
  CHECK(headingChange(170 * kDeg, -170 * kDeg) == doctest::Approx(20 * kDeg));
  CHECK(headingChange(-3.0, 3.0) == doctest::Approx(2 * std::numbers::pi - 6.0));
}

TEST_CASE("rrt: eq. 9 terms of known motions on a known plane") {
  // z rises 10° to the east: driving east pitches 10°, driving north rolls 10°.
  const double g = std::tan(10 * kDeg);
  Dem d = demFrom(40, 40, 0.25, [g](double x, double) { return g * x; });
  const auto cls = allClass(d, TerrainClass::Traversable);
  TerrainEdgeModel m(d, cls, wholeMap(d), 15 * kDeg, 0.0625);
  const TerrainCostWeights w;  // 0.1, 0.4, 0.4, 0.1 over 1 m, 15°, 15°, 60°

  EdgeTerms east = m.edgeTerms({3, 5}, {4, 5});
  CHECK(east.length == doctest::Approx(1.0));
  CHECK(east.pitch == doctest::Approx(10 * kDeg));
  CHECK(east.roll == doctest::Approx(0.0));
  CHECK(east.headingChange == 0.0);
  CHECK(east.cost(w) == doctest::Approx(0.1 * 1.0 + 0.4 * 10.0 / 15.0));

  // Downhill (west) pitches −10°: |θ| counts the same.
  CHECK(m.edgeTerms({4, 5}, {3.5, 5}).cost(w) == doctest::Approx(0.1 * 0.5 + 0.4 * 10.0 / 15.0));

  // North after heading east: roll 10°, a 90° turn.
  EdgeTerms north = m.edgeTerms({5, 3}, {5, 4}, 0.0);
  CHECK(north.roll == doctest::Approx(10 * kDeg));
  CHECK(north.pitch == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(north.headingChange == doctest::Approx(90 * kDeg));
  CHECK(north.cost(w) == doctest::Approx(0.1 + 0.4 * 10.0 / 15.0 + 0.1 * 90.0 / 60.0));

  // North-east: pitch = atan(g·cos45°) = roll.
  EdgeTerms ne = m.edgeTerms({3, 3}, {3.6, 3.6}, 90 * kDeg);
  const double a = std::atan(g * std::sqrt(0.5));
  CHECK(ne.pitch == doctest::Approx(a));
  CHECK(ne.roll == doctest::Approx(a));
  CHECK(ne.headingChange == doctest::Approx(45 * kDeg));
  CHECK(ne.cost(w) ==
        doctest::Approx(0.1 * 0.6 * std::sqrt(2.0) + 0.8 * a / (15 * kDeg) + 0.1 * 45.0 / 60.0));

  // A polyline: what the planner minimises (Δψ on the first edge only) vs every turn charged.
  std::vector<Eigen::Vector2d> path{{3, 3}, {4, 3}, {4, 4}};
  const double e1 = 0.1 + 0.4 * 10.0 / 15.0, e2 = 0.1 + 0.4 * 10.0 / 15.0;
  CHECK(pathCost(m, path, 0.0, w, false) == doctest::Approx(e1 + e2));
  CHECK(pathCost(m, path, 0.0, w, true) == doctest::Approx(e1 + e2 + 0.1 * 90.0 / 60.0));
  CHECK(pathCost(m, path, std::numbers::pi, w, false) ==
        doctest::Approx(e1 + e2 + 0.1 * 180.0 / 60.0));
}

TEST_CASE("rrt: validity rejects impassable cells, nodata, the bounds and attitudes >= 15°") {
  // Flat 0.25 m map (8 m × 8 m) with one impassable cell at (4.1, 4.1).
  Dem d = flatDem(32, 32, 0.25);
  auto cls = allClass(d, TerrainClass::Traversable);
  setCell(cls, {4.1, 4.1}, TerrainClass::Impassable);
  setCell(cls, {6.1, 6.1}, TerrainClass::HighRisk);
  TerrainEdgeModel m(d, cls, {{1, 1}, {7, 7}}, 15 * kDeg, 0.0625);
  CHECK(m.edgeValid({3.0, 4.1}, {3.95, 4.1}));       // stops short of it (the cell spans x 4..4.25)
  CHECK_FALSE(m.edgeValid({3.6, 4.1}, {4.6, 4.1}));  // crosses the impassable cell
  CHECK_FALSE(m.edgeValid({4.1, 3.6}, {4.1, 4.4}));
  CHECK(m.edgeValid({3.6, 4.6}, {4.6, 4.6}));  // passes north of it
  CHECK_FALSE(m.pointValid({4.1, 4.1}));
  CHECK(m.edgeValid({5.8, 6.1}, {6.6, 6.1}));        // high risk is allowed on flat ground
  CHECK_FALSE(m.edgeValid({6.5, 6.5}, {7.5, 6.5}));  // leaves the bounds
  CHECK_FALSE(m.pointValid({0.5, 3}));

  // A 20° plane rising east, classes forced traversable so only the attitude limit decides:
  // uphill pitches 20° (invalid); the diagonal has roll = pitch = atan(tan20°·cos45°) ≈ 14.4°.
  Dem steep = demFrom(32, 32, 0.25, [](double x, double) { return std::tan(20 * kDeg) * x; });
  const auto steepCls = allClass(steep, TerrainClass::Traversable);
  TerrainEdgeModel s(steep, steepCls, wholeMap(steep), 15 * kDeg, 0.0625);
  CHECK_FALSE(s.edgeValid({3, 3}, {3.8, 3}));
  CHECK_FALSE(s.edgeValid({3, 3}, {3, 3.8}));  // across the slope: roll 20°
  CHECK(s.edgeValid({3, 3}, {3.6, 3.6}));
  TerrainEdgeModel tight(steep, steepCls, wholeMap(steep), 14 * kDeg, 0.0625);
  CHECK_FALSE(tight.edgeValid({3, 3}, {3.6, 3.6}));
  // The real classes of a 20° plane are impassable everywhere.
  const auto realCls = terrain::traversability(steep).classes;
  TerrainEdgeModel real(steep, realCls, wholeMap(steep), 15 * kDeg, 0.0625);
  CHECK_FALSE(real.pointValid({3, 3}));

  // A nodata cell and the cells whose bilinear surface needs it.
  Dem holes = flatDem(32, 32, 0.25);
  holes.z(16, 16) = std::nanf("");
  auto holeCls = terrain::traversability(holes).classes;
  TerrainEdgeModel h(holes, holeCls, wholeMap(holes), 15 * kDeg, 0.0625);
  const Eigen::Vector2d hole = cellToLocal(holes.geometry(), {16, 16});
  CHECK_FALSE(h.pointValid(hole));
  CHECK_FALSE(h.edgeValid(hole - Eigen::Vector2d(1, 0), hole + Eigen::Vector2d(1, 0)));
  CHECK(h.edgeValid(hole + Eigen::Vector2d(-1, 1), hole + Eigen::Vector2d(1, 1)));
}

TEST_CASE("rrt: flat map gives a straight-ish exact path costing W_R·length/N_R") {
  Dem d = flatDem(40, 40, 0.25);  // 10 m × 10 m
  auto cls = allClass(d, TerrainClass::Traversable);
  const Eigen::Vector2d start(2.5, 5), goal(7.5, 5);
  RrtParams p;
  p.seed = 11;
  PathResult r = planPath(d, cls, start, 0.0, goal, p);
  REQUIRE(r.status == PathStatus::Exact);
  REQUIRE(r.waypoints.size() >= 6);  // edges of at most 1 m over 5 m
  CHECK(r.waypoints.front() == start);
  CHECK(r.waypoints.back() == goal);
  CHECK(r.goalDistance == 0.0);
  for (std::size_t i = 0; i + 1 < r.waypoints.size(); ++i)
    CHECK((r.waypoints[i + 1] - r.waypoints[i]).norm() <= p.range + 1e-9);
  const double len = polylineLength(r.waypoints);
  CHECK(len >= 5.0);
  CHECK(len < 5.0 * 1.05);
  for (const auto& w : r.waypoints) CHECK(std::abs(w.y() - 5.0) < 0.5);
  // No roll or pitch on flat ground: R plus the first edge's turn from the start heading.
  const TerrainCostWeights w;
  const Eigen::Vector2d e0 = r.waypoints[1] - r.waypoints[0];
  const double turn0 = std::abs(std::atan2(e0.y(), e0.x()));
  CHECK(r.cost == doctest::Approx(w.wR * len / w.nR + w.wPsi * turn0 / w.nPsi));
  CHECK(r.cost == doctest::Approx(0.1 * len).epsilon(0.05));
  CHECK(r.costWithTurns >= r.cost);
  CHECK(r.vertices >= 1250);
}

TEST_CASE("rrt: a wall of impassable cells with a gap: the path goes through the gap") {
  // 12 m × 12 m flat map; an impassable wall at 5.75 <= x < 6.25 with a gap at 4.5 <= y < 5.25.
  //   y
  //   6 |      #
  //   5 |  S   .   G      (S = (3, 3.5), G = (9, 3.5); the bounds reach y = 5.5)
  //   4 |      #
  //   3 |      #
  Dem d = flatDem(48, 48, 0.25);
  auto cls = allClass(d, TerrainClass::Traversable);
  for (int r = 0; r < 48; ++r)
    for (int c = 23; c < 25; ++c) {
      Eigen::Vector2d p = cellToLocal(d.geometry(), {r, c});
      if (p.y() < 4.5 || p.y() >= 5.25)
        cls(r, c) = static_cast<std::uint8_t>(TerrainClass::Impassable);
    }
  const Eigen::Vector2d start(3, 3.5), goal(9, 3.5);
  RrtParams p;
  p.seed = 3;
  PathResult r = planPath(d, cls, start, 0.0, goal, p);
  REQUIRE(r.status == PathStatus::Exact);
  TerrainEdgeModel m(d, cls, searchBounds(d.geometry(), start, goal, p.clearance), p.attitudeLimit,
                     0.0625);
  int crossings = 0;
  for (std::size_t i = 0; i + 1 < r.waypoints.size(); ++i) {
    const Eigen::Vector2d a = r.waypoints[i], b = r.waypoints[i + 1];
    CHECK(m.edgeValid(a, b));
    if ((a.x() < 6.0) != (b.x() < 6.0)) {
      const double y = a.y() + (b.y() - a.y()) * (6.0 - a.x()) / (b.x() - a.x());
      CHECK(y >= 4.5);
      CHECK(y < 5.25);
      ++crossings;
    }
  }
  CHECK(crossings >= 1);
  // Closing the gap leaves only an approximate path on the start's side.
  for (int r2 = 0; r2 < 48; ++r2)
    for (int c = 23; c < 25; ++c) cls(r2, c) = static_cast<std::uint8_t>(TerrainClass::Impassable);
  PathResult blocked = planPath(d, cls, start, 0.0, goal, p);
  CHECK(blocked.status == PathStatus::Approximate);
  CHECK(blocked.waypoints.back().x() < 5.75);
  CHECK(blocked.goalDistance > 3.0);
}

TEST_CASE("rrt: invalid start and goal") {
  Dem d = flatDem(40, 40, 0.25);
  d.z(5, 30) = std::nanf("");  // nodata in the north-east
  auto cls = terrain::traversability(d).classes;
  setCell(cls, {2, 2}, TerrainClass::Impassable);
  const Eigen::Vector2d noData = cellToLocal(d.geometry(), {5, 30});
  // A start on an impassable cell (the simulated rover cut a corner) is escaped: the checks are
  // waived within 0.5 m of it, so the rover can drive off; off the map or on nodata it is invalid.
  PathResult escaped = planPath(d, cls, {2, 2}, 0, {5, 5});
  CHECK(escaped.status == PathStatus::Exact);
  CHECK(planPath(d, cls, noData, 0, {5, 5}).status == PathStatus::InvalidStart);
  CHECK(planPath(d, cls, {-1, 5}, 0, {5, 5}).status == PathStatus::InvalidStart);
  CHECK(planPath(d, cls, {5, 5}, 0, {12, 5}).status == PathStatus::InvalidGoal);
  CHECK(planPath(d, cls, {5, 5}, 0, noData).status == PathStatus::InvalidGoal);
  CHECK(planPath(d, cls, {5, 5}, 0, {2, 2}).status == PathStatus::InvalidGoal);
  PathResult same = planPath(d, cls, {5, 5}, 0, {5, 5});
  CHECK(same.status == PathStatus::Exact);
  CHECK(same.waypoints.size() == 1);
  CHECK(enumName(PathStatus::InvalidGoal) == "invalid_goal");
}

TEST_CASE("rrt: same seed gives the identical path, another seed a different one") {
  // Gentle hills so that costs differ between paths.
  Dem d = demFrom(48, 48, 0.25,
                  [](double x, double y) { return 0.3 * std::sin(0.9 * x) * std::cos(0.7 * y); });
  auto cls = terrain::traversability(d).classes;
  const Eigen::Vector2d start(3, 3), goal(8, 7);
  RrtParams p;
  p.seed = 42;
  PathResult a = planPath(d, cls, start, 0.3, goal, p);
  PathResult b = planPath(d, cls, start, 0.3, goal, p);
  REQUIRE(a.hasPath());
  CHECK(a.waypoints == b.waypoints);
  CHECK(a.cost == b.cost);
  CHECK(a.iterations == b.iterations);
  p.seed = 43;
  PathResult c = planPath(d, cls, start, 0.3, goal, p);
  REQUIRE(c.hasPath());
  CHECK(c.waypoints != a.waypoints);
}

TEST_CASE("rrt: the tree grows to exactly maxVertices vertices, whatever the clock") {
  Dem d = flatDem(40, 40, 0.25);
  auto cls = allClass(d, TerrainClass::Traversable);
  PathResult r = planPath(d, cls, {2, 2}, 0, {8, 8});
  CHECK(r.vertices == 1250);  // OMPL PlannerData of the tree; one vertex per iteration at most
  CHECK(r.iterations >= 1249);
  RrtParams p;
  p.maxVertices = 300;
  PathResult small = planPath(d, cls, {2, 2}, 0, {8, 8}, p);
  CHECK(small.vertices == 300);

  // A start walled in on all sides can never grow the tree: the iteration cap ends the search.
  auto boxed = cls;
  for (int r2 = 18; r2 <= 22; ++r2)
    for (int c = 18; c <= 22; ++c)
      if (r2 == 18 || r2 == 22 || c == 18 || c == 22)
        boxed(r2, c) = static_cast<std::uint8_t>(TerrainClass::Impassable);
  const Eigen::Vector2d inside = cellToLocal(d.geometry(), {20, 20});
  p = {};
  p.maxIterations = 3000;
  PathResult stuck = planPath(d, boxed, inside, 0, {8, 8}, p);
  CHECK(stuck.iterations == 3000);
  CHECK(stuck.vertices < 1250);
  CHECK(stuck.status == PathStatus::Approximate);
  for (const auto& w : stuck.waypoints) CHECK((w - inside).lpNorm<Eigen::Infinity>() < 0.75);
}

TEST_CASE("rrt: a cancelled token stops the search") {
  Dem d = flatDem(40, 40, 0.25);
  auto cls = allClass(d, TerrainClass::Traversable);
  CancelToken token;
  token.cancel();
  PathResult r = planPath(d, cls, {2, 2}, 0, {8, 8}, {}, {}, &token);
  CHECK(r.status == PathStatus::Cancelled);
  CHECK(r.waypoints.empty());
}

TEST_CASE("rrt: the cost steers around a hill that the straight line climbs") {
  // A Gaussian hill (peak slope ≈ 12°) centred on the straight line from start to goal.
  Dem d = demFrom(48, 48, 0.25, [](double x, double y) {
    return 0.6 * std::exp(-((x - 6) * (x - 6) + (y - 6) * (y - 6)) / (2 * 0.9 * 0.9));
  });
  auto cls = terrain::traversability(d).classes;
  const Eigen::Vector2d start(3, 6), goal(9, 6);
  RrtParams p;
  p.seed = 5;
  PathResult r = planPath(d, cls, start, 0.0, goal, p);
  REQUIRE(r.status == PathStatus::Exact);
  // The straight line cut into 1 m edges costs more than the planned path.
  std::vector<Eigen::Vector2d> straight;
  for (int i = 0; i <= 6; ++i) straight.push_back(start + (goal - start) * (i / 6.0));
  TerrainEdgeModel m(d, cls, searchBounds(d.geometry(), start, goal, p.clearance), p.attitudeLimit,
                     0.0625);
  CHECK(r.cost < pathCost(m, straight, 0.0, TerrainCostWeights{}, false));
  double farthest = 0;
  for (const auto& w : r.waypoints) farthest = std::max(farthest, std::abs(w.y() - 6.0));
  CHECK(farthest > 1.0);  // it left the straight line
}

TEST_CASE("rrt: two threads planning different problems match sequential runs") {
  Dem d =
      demFrom(64, 64, 0.25, [](double x, double y) { return 0.25 * std::sin(0.8 * x + 0.3 * y); });
  auto cls = terrain::traversability(d).classes;
  struct Problem {
    Eigen::Vector2d start, goal;
    double heading;
    std::uint64_t seed;
  };
  const std::vector<Problem> problems{{{3, 3}, {8, 6}, 0.0, 7},
                                      {{12, 12}, {7, 10}, 3.0, 8},
                                      {{4, 12}, {9, 13}, 1.0, 9},
                                      {{13, 3}, {10, 7}, -1.5, 10}};
  auto run = [&](const Problem& pr) {
    RrtParams p;
    p.seed = pr.seed;
    return planPath(d, cls, pr.start, pr.heading, pr.goal, p);
  };
  std::vector<PathResult> sequential;
  for (const auto& pr : problems) sequential.push_back(run(pr));
  std::vector<PathResult> parallel(problems.size());
  std::thread t0([&] {
    for (std::size_t i = 0; i < problems.size(); i += 2) parallel[i] = run(problems[i]);
  });
  std::thread t1([&] {
    for (std::size_t i = 1; i < problems.size(); i += 2) parallel[i] = run(problems[i]);
  });
  t0.join();
  t1.join();
  for (std::size_t i = 0; i < problems.size(); ++i) {
    CAPTURE(i);
    CHECK(sequential[i].hasPath());
    CHECK(parallel[i].status == sequential[i].status);
    CHECK(parallel[i].waypoints == sequential[i].waypoints);
    CHECK(parallel[i].cost == sequential[i].cost);
    CHECK(parallel[i].vertices == sequential[i].vertices);
  }
}

TEST_CASE("rrt: edge roll and pitch are terrain::attitudeAt's, maximised over the samples") {
  Dem d = demFrom(40, 40, 0.25, [](double x, double y) {
    return 0.2 * std::sin(1.3 * x) + 0.15 * std::cos(0.9 * y + 0.4 * x);
  });
  const auto cls = allClass(d, TerrainClass::Traversable);
  TerrainEdgeModel m(d, cls, wholeMap(d), 15 * kDeg, 0.05);
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> edges{
      {{2, 2}, {2.9, 2.3}}, {{5, 5}, {4.2, 5.5}}, {{3, 7}, {3.1, 6.1}}, {{6, 2}, {6.7, 2.7}}};
  int valid = 0;
  for (const auto& [a, b] : edges) {
    const Eigen::Vector2d dir = b - a;
    const double heading = std::atan2(dir.y(), dir.x());
    const int n = static_cast<int>(std::ceil(dir.norm() / 0.05));
    double roll = 0, pitch = 0;
    bool withinLimit = true;
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2d p = a + dir * (static_cast<double>(i) / n);
      auto att = terrain::attitudeAt(d, p.x(), p.y(), heading);
      REQUIRE(att);
      roll = std::max(roll, std::abs(att->roll));
      pitch = std::max(pitch, std::abs(att->pitch));
      withinLimit =
          withinLimit && std::abs(att->roll) < 15 * kDeg && std::abs(att->pitch) < 15 * kDeg;
    }
    EdgeTerms t = m.edgeTerms(a, b);
    CHECK(t.roll == doctest::Approx(roll).epsilon(1e-12));
    CHECK(t.pitch == doctest::Approx(pitch).epsilon(1e-12));
    CHECK(m.edgeValid(a, b) == withinLimit);
    valid += withinLimit;
  }
  CHECK(valid > 0);  // both outcomes are exercised
  CHECK(valid < static_cast<int>(edges.size()));
}

TEST_CASE("rrt: the patch evaluation is the exact maximum over the edge, never below the samples") {
  for (const bool perRow : {false, true}) {
    CAPTURE(perRow);
    // A rough literal surface: the gradient jumps at every row and column of cell centres.
    Dem d = demFrom(24, 24, 0.25, [](double x, double y) {
      return 0.2 * std::sin(1.3 * x) + 0.15 * std::cos(0.9 * y + 0.4 * x) + 0.03 * std::sin(7.0 * x * y);
    });
    // Per-row cell widths (a geographic grid): the width changes halfway between rows of centres.
    if (perRow)
      for (int r = 0; r < 24; ++r) d.rowCellWidth.push_back(0.25 * (0.8 + 0.02 * r));
    const auto cls = allClass(d, TerrainClass::Traversable);
    TerrainEdgeModel sampled(d, cls, wholeMap(d), 15 * kDeg, 0.0625);
    TerrainEdgeModel dense(d, cls, wholeMap(d), 15 * kDeg, 1e-5);
    TerrainEdgeModel patch(d, cls, wholeMap(d), 15 * kDeg, 0.0625);
    patch.setEvaluation(EdgeEvaluation::Patch);
    const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> edges{
        {{2, 2}, {2.9, 2.3}},     {{5, 5}, {4.2, 5.5}},   {{3, 4}, {3.1, 3.1}},
        {{1.375, 1.2}, {2.125, 1.2}},  // along a row, from a column of centres to one
        {{0.0, 0.0}, {0.6, 0.1}},      // from the map's corner, through the clamped border half cell
        {{4, 3}, {4, 3.9}},            // due north: no column crossed
        {{2.2, 2.2}, {2.2, 2.2}}};     // zero length
    for (const auto& edge : edges) {
      // Named variables, not a structured binding: clang 14 cannot capture one in CAPTURE's lambda.
      const Eigen::Vector2d& a = edge.first;
      const Eigen::Vector2d& b = edge.second;
      CAPTURE(a.transpose());
      CAPTURE(b.transpose());
      const EdgeTerms p = patch.edgeTerms(a, b), s = sampled.edgeTerms(a, b), e = dense.edgeTerms(a, b);
      CHECK(p.length == s.length);
      CHECK(p.roll >= s.roll - 1e-12);  // the same point in another order of operations
      CHECK(p.pitch >= s.pitch - 1e-12);
      // The dense samples approach the exact maximum from below (10 µm apart: within 1e-4 rad).
      CHECK(p.roll == doctest::Approx(e.roll).epsilon(1e-4));
      CHECK(p.pitch == doctest::Approx(e.pitch).epsilon(1e-4));
      CHECK(p.roll >= e.roll - 1e-12);
      CHECK(p.pitch >= e.pitch - 1e-12);
    }
  }
  // On a plane the gradient is the same everywhere: both evaluations agree exactly.
  const double g = std::tan(10 * kDeg);
  Dem plane = demFrom(16, 16, 0.25, [g](double x, double y) { return g * x - 0.5 * g * y; });
  const auto planeClasses = allClass(plane, TerrainClass::Traversable);
  TerrainEdgeModel planeSampled(plane, planeClasses, wholeMap(plane), 15 * kDeg, 0.0625);
  TerrainEdgeModel planePatch(plane, planeClasses, wholeMap(plane), 15 * kDeg, 0.0625);
  planePatch.setEvaluation(EdgeEvaluation::Patch);
  const EdgeTerms ps = planeSampled.edgeTerms({1, 1}, {1.7, 1.6}), pp = planePatch.edgeTerms({1, 1}, {1.7, 1.6});
  CHECK(pp.roll == doctest::Approx(ps.roll).epsilon(1e-6));  // heights are floats
  CHECK(pp.pitch == doctest::Approx(ps.pitch).epsilon(1e-6));
}

TEST_CASE("rrt: the patch evaluation plans on the same terms, deterministically") {
  Dem d = demFrom(40, 40, 0.25, [](double x, double y) { return 0.2 * std::sin(1.3 * x) + 0.15 * std::cos(0.9 * y); });
  const auto cls = allClass(d, TerrainClass::Traversable);
  RrtParams p;
  p.maxVertices = 300;
  p.seed = 7;
  p.evaluation = EdgeEvaluation::Patch;
  const PathResult a = planPath(d, cls, {2, 2}, 0.0, {7, 6}, p);
  const PathResult b = planPath(d, cls, {2, 2}, 0.0, {7, 6}, p);
  REQUIRE(a.status == PathStatus::Exact);
  CHECK(a.waypoints == b.waypoints);
  // The reported cost is eq. 9 with the patch terms, which are never below the samples'.
  TerrainEdgeModel patch(d, cls, wholeMap(d), p.attitudeLimit, edgeResolutionOn(d.geometry(), p));
  patch.setEvaluation(EdgeEvaluation::Patch);
  TerrainEdgeModel sampled(d, cls, wholeMap(d), p.attitudeLimit, edgeResolutionOn(d.geometry(), p));
  CHECK(a.cost == doctest::Approx(pathCost(patch, a.waypoints, 0.0, {}, false)));
  CHECK(a.cost >= pathCost(sampled, a.waypoints, 0.0, {}, false) - 1e-12);
}

TEST_CASE("rrt: the grid neighbours answer what a linear scan answers, in the same order") {
  // Points in a 7 × 4 m box (some on its edges), queries inside it: nearestR over radii up to the
  // range and beyond a bucket, nearestK and nearest, against OMPL's brute-force structure.
  struct Pt {
    double x, y;
  };
  std::vector<Pt> pts;
  Rng rng(5);
  for (int i = 0; i < 600; ++i) pts.push_back({1 + 7 * rng.uniform(), 2 + 4 * rng.uniform()});
  pts.push_back({1, 2});
  pts.push_back({8, 6});
  pts.push_back({-3, 4});   // outside the box: kept in an edge bucket, still found
  pts.push_back({9.5, 7});
  // The grid computes distances itself, as OMPL's RealVectorStateSpace does (planeDistance).
  auto dist = [](Pt* const& a, Pt* const& b) {
    return planeDistance(Eigen::Vector2d(a->x, a->y), Eigen::Vector2d(b->x, b->y));
  };
  GridNearestNeighbors<Pt*> grid({1, 2}, {8, 6}, 0.5, [](Pt* const& p) { return Eigen::Vector2d(p->x, p->y); });
  ompl::NearestNeighborsLinear<Pt*> linear;
  linear.setDistanceFunction(dist);
  for (auto& p : pts) {
    grid.add(&p);
    linear.add(&p);
  }
  CHECK(grid.size() == pts.size());
  std::vector<Pt*> a, b;
  for (int q = 0; q < 200; ++q) {
    Pt query{1 + 7 * rng.uniform(), 2 + 4 * rng.uniform()};
    if (q % 10 == 0) query = {-5 + 15 * rng.uniform(), 0 + 8 * rng.uniform()};  // anywhere
    for (double r : {0.05, 0.3, 0.5, 1.0, 2.2, std::numeric_limits<double>::infinity()}) {
      grid.nearestR(&query, r, a);
      linear.nearestR(&query, r, b);
      REQUIRE(a == b);
    }
    for (std::size_t k : {1u, 3u, 17u}) {
      grid.nearestK(&query, k, a);
      linear.nearestK(&query, k, b);
      REQUIRE(a == b);
    }
    CHECK(grid.nearest(&query) == linear.nearest(&query));
  }
  // planeDistance is the number RRTstar's own distance function gives in R², bit for bit.
  auto space = std::make_shared<ompl::base::RealVectorStateSpace>(2);
  ompl::base::ScopedState<ompl::base::RealVectorStateSpace> s1(space), s2(space);
  for (int i = 0; i < 10000; ++i) {
    const Eigen::Vector2d u(-50 + 100 * rng.uniform(), 1e-3 * rng.uniform()), v(100 * rng.uniform(), -7 * rng.uniform());
    s1[0] = u.x();
    s1[1] = u.y();
    s2[0] = v.x();
    s2[1] = v.y();
    REQUIRE(planeDistance(u, v) == space->distance(s1.get(), s2.get()));
  }
  CHECK(grid.remove(&pts[7]));
  CHECK_FALSE(grid.remove(&pts[7]));
  CHECK(grid.size() == pts.size() - 1);
}
