#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "core/common/error.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "grid_literals.hpp"

using namespace rover;
using namespace rover::coverage;
using test::at;
using test::cellOf;

namespace {

// Records the cells sensed or entered at step 0 and every pose.
struct Recorder : EventSink {
  std::vector<std::vector<CellUpdate>> cellBatches;
  std::vector<std::vector<RoverPose>> poses;
  void cellsChanged(std::span<const CellUpdate> c) override {
    cellBatches.emplace_back(c.begin(), c.end());
  }
  void roverPoses(std::int64_t, std::span<const RoverPose> p) override {
    poses.emplace_back(p.begin(), p.end());
  }
};

CoverageParams onlySteps(CoverageParams p, int steps) {
  p.maxSteps = steps;
  p.coverage = 1.0;
  return p;
}

}  // namespace

TEST_CASE("sensing radius 1 sees the 8 neighbours, radius 2 the 24 cells around") {
  World w = test::worldFrom({
      ".....",
      ".....",
      ".....",
      ".....",
      ".....",
  });
  for (int radius : {1, 2}) {
    CoverageParams p = onlySteps({}, 1);
    p.senseRadius = radius;
    Recorder rec;
    runCoverage(w, {at(w, 2, 2, 0)}, p, &rec);
    // Step 0: the start cell entered, then every cell in the Chebyshev ball sensed.
    const auto& first = rec.cellBatches.at(0);
    CHECK(first.size() == (radius == 1 ? 1u + 8u : 1u + 24u));
  }
}

TEST_CASE("static cost: spiral turns left first, boustrophedon sweeps along x") {
  World w = test::worldFrom({
      ".....",
      ".....",
      ".....",
  });
  CoverageParams spiral = onlySteps({}, 1);
  auto r = runCoverage(w, {at(w, 1, 2, 0)}, spiral);
  CHECK(cellOf(w, r.rovers[0].cells[1]) == CellIndex{0, 2});  // heading E, left = north

  CoverageParams bous = onlySteps({}, 1);
  bous.pattern = "boustrophedon";
  r = runCoverage(w, {at(w, 1, 2, 2)}, bous);  // heading N: E/W lanes still win
  CHECK(cellOf(w, r.rovers[0].cells[1]).row == 1);
}

TEST_CASE("left and right get different costs: mirrored tables mirror the move") {
  World w = test::worldFrom({
      "...",
      "...",
      "...",
  });
  //                         straight L45  L90  L135 back R135 R90  R45
  CoverageParams left = test::withTable({0.9, 0.5, 0.1, 0.7, 0.95, 0.8, 0.2, 0.6});
  CoverageParams right = test::withTable({0.9, 0.6, 0.2, 0.8, 0.95, 0.7, 0.1, 0.5});
  left = onlySteps(left, 1);
  right = onlySteps(right, 1);
  CHECK(cellOf(w, runCoverage(w, {at(w, 1, 1, 0)}, left).rovers[0].cells[1]) == CellIndex{0, 1});
  CHECK(cellOf(w, runCoverage(w, {at(w, 1, 1, 0)}, right).rovers[0].cells[1]) == CellIndex{2, 1});
}

TEST_CASE("the visited penalty sends the rover to unvisited cells") {
  World w = test::worldFrom({
      "...",
      "...",
      "...",
  });
  // Reversing is the cheapest static move: without the penalty the rover would shuttle.
  CoverageParams p = test::withTable({0.3, 0.5, 0.4, 0.7, 0.0, 0.8, 0.45, 0.6});
  p = onlySteps(p, 2);
  auto r = runCoverage(w, {at(w, 1, 1, 0)}, p);
  const auto& cells = r.rovers[0].cells;
  CHECK(cellOf(w, cells[1]) == CellIndex{1, 0});  // reversed: west
  CHECK(cells[2] != cells[0]);                    // not back: the start is visited
  CHECK(r.rovers[0].revisits == 0);
}

TEST_CASE("the height term (β) steers round a step up (paper 000 eq. 3)") {
  World w = test::worldFrom({
      "...",
      "...",
      "...",
  });
  test::setHeights(w, {{10, 10, 10}, {0, 0, 0}, {0, 0, 0}});
  CoverageParams flat = onlySteps({}, 1);  // β = 0: spiral goes left = north, up the step
  auto r0 = runCoverage(w, {at(w, 1, 1, 0)}, flat);
  CHECK(cellOf(w, r0.rovers[0].cells[1]) == CellIndex{0, 1});
  CHECK(r0.metrics.maxPitchDeg == doctest::Approx(std::atan(10.0) * 180 / std::numbers::pi));

  CoverageParams risk = flat;
  risk.alpha = 0.3;
  risk.beta = 0.7;
  auto r1 = runCoverage(w, {at(w, 1, 1, 0)}, risk);
  CHECK(cellOf(w, r1.rovers[0].cells[1]).row != 0);
  CHECK(r1.metrics.maxPitchDeg == 0.0);
  CHECK(r1.metrics.energyJ < r0.metrics.energyJ);
}

TEST_CASE("stop rule: visited >= goal·(n − known obstacles), counts kept incrementally") {
  World w = test::worldFrom({
      "....",
      ".#..",
      "....",
      "....",
  });
  CoverageParams p;
  p.coverage = 0.5;
  auto r = runCoverage(w, {at(w, 0, 0, 0)}, p);
  CHECK(r.stop == StopReason::GoalReached);
  CHECK(r.metrics.visitedCells == 8);  // ceil(0.5 · (16 − 1))
  p.coverage = 1.0;
  r = runCoverage(w, {at(w, 0, 0, 0)}, p);
  CHECK(r.metrics.visitedCells == 15);
  CHECK(r.metrics.coverage == 1.0);
  CHECK(r.curve.back().visited == 15);
  CHECK(r.curve.front().visited == 1);
}

TEST_CASE("step budget and cancellation stop the run") {
  World w = generateWorld({});
  auto starts = randomStarts(w, 1, 1);
  CoverageParams p;
  p.maxSteps = 5;
  auto r = runCoverage(w, starts, p);
  CHECK(r.stop == StopReason::StepBudget);
  CHECK(r.metrics.steps == 5);
  CHECK(r.rovers[0].moves <= 5);

  CancelToken cancelled;
  cancelled.cancel();
  r = runCoverage(w, starts, CoverageParams{}, nullptr, &cancelled);
  CHECK(r.stop == StopReason::Cancelled);
  CHECK(r.metrics.steps == 0);

  struct CancelAt3 : EventSink {
    CancelToken token;
    void roverPoses(std::int64_t step, std::span<const RoverPose>) override {
      if (step == 3) token.cancel();
    }
  } sink;
  r = runCoverage(w, starts, CoverageParams{}, &sink, &sink.token);
  CHECK(r.stop == StopReason::Cancelled);
  CHECK(r.metrics.steps == 3);
}

TEST_CASE("never enters an obstacle, never leaves the grid, moves are 8-adjacent") {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    WorldParams wp;
    wp.rows = 25;
    wp.cols = 17;
    wp.obstacleFraction = 0.2;
    wp.seed = seed;
    World w = generateWorld(wp);
    for (bool circ : {false, true}) {
      CoverageParams p;
      p.circumnavigate = circ;
      p.pattern = seed % 2 ? "spiral" : "boustrophedon";
      auto r = runCoverage(w, randomStarts(w, 1, seed), p);
      const auto& cells = r.rovers[0].cells;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        REQUIRE(cells[i] >= 0);
        REQUIRE(cells[i] < w.geometry().cellCount());
        REQUIRE_FALSE(w.isObstacle(cells[i]));
        if (i > 0) {
          CellIndex a = cellOf(w, cells[i - 1]), b = cellOf(w, cells[i]);
          REQUIRE(std::max(std::abs(a.row - b.row), std::abs(a.col - b.col)) == 1);
        }
      }
    }
  }
}

TEST_CASE("same seed, same result, another seed, another result") {
  auto run = [](std::uint64_t seed) {
    WorldParams wp;
    wp.seed = seed;
    World w = generateWorld(wp);
    return runCoverage(w, randomStarts(w, 2, seed), CoverageParams{});
  };
  auto a = run(7), b = run(7), c = run(8);
  CHECK(a.rovers[0].cells == b.rovers[0].cells);
  CHECK(a.rovers[1].cells == b.rovers[1].cells);
  CHECK(a.metrics.energyJ == b.metrics.energyJ);
  CHECK(a.rovers[0].cells != c.rovers[0].cells);
}

TEST_CASE("distance counts diagonals as √2 cells, path length ratio is moves / n") {
  World w = test::worldFrom(
      {
          "...",
          "...",
          "...",
      },
      2.0);
  CoverageParams p = onlySteps(test::withTable({0.9, 0.1, 0.5, 0.7, 0.95, 0.8, 0.6, 0.2}), 1);
  auto r = runCoverage(w, {at(w, 2, 0, 0)}, p);  // L45 from east = north-east
  CHECK(cellOf(w, r.rovers[0].cells[1]) == CellIndex{1, 1});
  CHECK(r.metrics.distanceM == doctest::Approx(2.0 * std::sqrt(2.0)));
  CHECK(r.metrics.pathLengthRatio == doctest::Approx(1.0 / 9.0));
}

TEST_CASE("obstacle circumnavigation follows the contour and regains the line") {
  World w = test::worldFrom({
      ".......",
      ".......",
      "...#...",
      ".......",
      ".......",
  });
  // Straight on is preferred; without circumnavigation the rover turns away at the rock.
  CoverageParams p = onlySteps(test::withTable({0.0, 0.5, 0.3, 0.7, 0.9, 0.8, 0.4, 0.6}), 5);
  auto plain = runCoverage(w, {at(w, 2, 0, 0)}, p);
  CHECK(cellOf(w, plain.rovers[0].cells[3]) == CellIndex{1, 2});  // turned left (north)

  p.circumnavigate = true;
  auto circ = runCoverage(w, {at(w, 2, 0, 0)}, p);
  std::vector<CellIndex> path;
  for (int c : circ.rovers[0].cells) path.push_back(cellOf(w, c));
  REQUIRE(path.size() == 6);
  CHECK(path[2] == CellIndex{2, 2});
  CHECK(path[3] == CellIndex{1, 3});  // round the rock, obstacle on the right
  CHECK(path[4] == CellIndex{2, 4});  // back on row 2 beyond it
  CHECK(path[5] == CellIndex{2, 5});  // and on along the original line
}

TEST_CASE("bad starts are rejected naming the rover") {
  World w = test::worldFrom({
      "..#",
      "...",
  });
  CoverageParams p;
  CHECK_THROWS_WITH_AS(runCoverage(w, {at(w, 0, 0, 0), at(w, 0, 2, 0)}, p),
                       "rovers[1]: start is on an obstacle", Error);
  CHECK_THROWS_WITH_AS(runCoverage(w, {at(w, 0, 0, 0), at(w, 0, 0, 3)}, p),
                       "rovers[1]: two rovers start on one cell", Error);
  CHECK_THROWS_WITH_AS(runCoverage(w, {{99, 0}}, p), "rovers[0]: start is outside the grid", Error);
  CHECK_THROWS_WITH_AS(runCoverage(w, {}, p), "between 1 and 64 rovers are supported", Error);
  p.alpha = 0.2;
  CHECK_THROWS_WITH_AS(runCoverage(w, {at(w, 0, 0, 0)}, p),
                       "beta: alpha + beta must equal 1 (paper 000 eq. 3)", Error);
}
