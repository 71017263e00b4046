#include <doctest/doctest.h>

#include "core/coverage/coverage_planner.hpp"
#include "grid_literals.hpp"

using namespace rover;
using namespace rover::coverage;
using test::at;

TEST_CASE("frontier: sealed regions are reported, not chased, and the run terminates") {
  World w = test::worldFrom({
      "......",
      "......",
      "....##",
      "....#.",
  });
  CoverageParams p;
  p.frontier = true;
  p.coverage = 1.0;
  auto r = runCoverage(w, {at(w, 0, 0, 0)}, p);
  CHECK(r.stop == StopReason::NothingLeft);
  CHECK(r.metrics.unreachableCells == 1);
  CHECK(r.metrics.reachableCells == 20);
  CHECK(r.metrics.coverageReachable == 1.0);
  CHECK(r.metrics.steps < 100);

  // Without frontier the myopic rover never learns the pocket is sealed: budget runs out.
  p.frontier = false;
  p.maxSteps = 500;
  auto plain = runCoverage(w, {at(w, 0, 0, 0)}, p);
  CHECK(plain.stop == StopReason::StepBudget);
  CHECK(plain.metrics.steps == 500);
}

TEST_CASE("frontier walks the shortest known path to the nearest unexplored cell") {
  // A dead-end corridor: once the rover is at the end, every neighbour is visited, so it must
  // walk back through the corridor to the open area.
  World w = test::worldFrom({
      "#######",
      "#.....#",
      "###.###",
      "#.....#",
      "#######",
  });
  CoverageParams p;
  p.frontier = true;
  p.coverage = 1.0;
  auto r = runCoverage(w, {at(w, 1, 1, 0)}, p);
  CHECK(r.stop == StopReason::GoalReached);
  CHECK(r.metrics.coverage == 1.0);
  // 11 free cells: 10 first visits plus the backtracking, bounded by the corridor length.
  CHECK(r.metrics.moves <= 10 + 4);
}

TEST_CASE("frontier reaches every reachable cell on random worlds") {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    WorldParams wp;
    wp.rows = wp.cols = 20;
    wp.obstacleFraction = 0.25;  // sealed pockets are common at this density
    wp.seed = seed;
    World w = generateWorld(wp);
    CoverageParams p;
    p.frontier = true;
    p.coverage = 1.0;
    auto r = runCoverage(w, randomStarts(w, 1, seed), p);
    CHECK(r.stop != StopReason::StepBudget);
    CHECK(r.metrics.coverageReachable == 1.0);
    CHECK(r.metrics.visitedCells + r.metrics.unreachableCells == r.metrics.freeCells);
  }
}
