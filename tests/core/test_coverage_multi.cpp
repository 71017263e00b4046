#include <doctest/doctest.h>

#include <set>

#include "core/coverage/coverage_planner.hpp"
#include "grid_literals.hpp"

using namespace rover;
using namespace rover::coverage;
using test::at;

namespace {
// Checks after every step that no two rovers share a cell.
struct DistinctPoses : EventSink {
  int violations = 0;
  int steps = 0;
  void roverPoses(std::int64_t, std::span<const RoverPose> poses) override {
    ++steps;
    std::set<std::pair<double, double>> seen;
    for (const auto& p : poses) violations += !seen.insert({p.x, p.y}).second;
  }
};
}  // namespace

TEST_CASE("two rovers never share a cell after a step (overlap and voronoi)") {
  for (auto mode : {TeamMode::Overlap, TeamMode::Voronoi}) {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      WorldParams wp;
      wp.rows = wp.cols = 12;
      wp.obstacleFraction = 0.1;
      wp.seed = seed;
      World w = generateWorld(wp);
      CoverageParams p;
      p.mode = mode;
      DistinctPoses sink;
      runCoverage(w, randomStarts(w, 6, seed), p, &sink);
      CHECK(sink.steps > 1);
      CHECK(sink.violations == 0);
    }
  }
}

TEST_CASE("a rover boxed in by team mates waits instead of moving") {
  World w = test::worldFrom({
      "#####",
      ".....",
  });
  CoverageParams p;
  p.coverage = 1.0;
  p.maxSteps = 1;
  // Rovers 0 and 1 have no free neighbour: each is held by a team mate; rover 2 can move.
  auto r = runCoverage(w, {at(w, 1, 0, 0), at(w, 1, 1, 0), at(w, 1, 2, 0)}, p);
  CHECK(r.rovers[0].waits == 1);
  CHECK(r.rovers[1].waits == 1);
  CHECK(r.rovers[2].moves == 1);
  CHECK(test::cellOf(w, r.rovers[2].cells[1]) == CellIndex{1, 3});
}

TEST_CASE("overlap: one shared map, the team stops together on team coverage") {
  World w = test::worldFrom({
      "........",
      "........",
      "........",
      "........",
  });
  CoverageParams p;
  p.coverage = 1.0;
  auto r = runCoverage(w, {at(w, 0, 0, 0), at(w, 3, 7, 4)}, p);
  CHECK(r.stop == StopReason::GoalReached);
  CHECK(r.metrics.visitedCells == 32);
  CHECK(r.region.empty());
  // Each rover alone would need >= 31 moves; sharing the map they split the work.
  CHECK(r.metrics.makespan < 31);
  CHECK(r.metrics.moves == r.rovers[0].moves + r.rovers[1].moves);
}

TEST_CASE("voronoi: cells go to the nearest start, each rover stays in its region") {
  World w = test::worldFrom({
      "......",
      "......",
      "......",
      "......",
  });
  CoverageParams p;
  p.mode = TeamMode::Voronoi;
  p.coverage = 1.0;
  auto r = runCoverage(w, {at(w, 0, 0, 0), at(w, 3, 5, 4)}, p);
  REQUIRE(r.region.size() == 24);
  // Nearest start by Euclidean distance in cells; ties go to the lower rover index.
  CHECK(r.region[test::idx(w, 0, 2)] == 0);
  CHECK(r.region[test::idx(w, 3, 3)] == 1);
  CHECK(r.region[test::idx(w, 0, 5)] == 1);  // 5 cells from rover 0, 3 from rover 1
  for (int k = 0; k < 2; ++k)
    for (int c : r.rovers[k].cells) CHECK(r.region[c] == k);
  CHECK(r.metrics.visitedCells == 24);
}

TEST_CASE("voronoi: a rover stops when its own region reaches the goal") {
  World w = test::worldFrom({
      "..........",
      "..........",
  });
  CoverageParams p;
  p.mode = TeamMode::Voronoi;
  p.coverage = 1.0;
  // Rover 0 owns columns 0..1, rover 1 the other 8 columns.
  auto r = runCoverage(w, {at(w, 0, 0, 0), at(w, 0, 3, 0)}, p);
  CHECK(r.rovers[0].moves == 3);  // its 4 cells, then it stops
  CHECK(r.rovers[1].moves > r.rovers[0].moves);
  CHECK(r.metrics.makespan == r.rovers[1].moves);
  CHECK(r.stop == StopReason::GoalReached);
}
