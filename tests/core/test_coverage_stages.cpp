// The coverage engine's stages (.decisions/0001): the neighbour range, the rover limit, the
// energy of flat moves looked up, and the perfect plant's sensing of only the cells a move brings
// into range.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/common/error.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/energy.hpp"
#include "core/coverage/knowledge_map.hpp"
#include "core/coverage/recorder.hpp"
#include "core/grid/neighbours.hpp"
#include "core/planning/rover_limits.hpp"
#include "grid_literals.hpp"

using namespace rover;
using namespace rover::coverage;

namespace {

std::vector<int> dirsAround(const GridGeometry& g, CellIndex c, int firstDir) {
  std::vector<int> out;
  for (const Neighbour& n : neighbours8(g, c, firstDir)) {
    CHECK(n.row == c.row + kDirRow[n.dir]);
    CHECK(n.col == c.col + kDirCol[n.dir]);
    CHECK(n.index == g.index(n.row, n.col));
    out.push_back(n.dir);
  }
  return out;
}

}  // namespace

TEST_CASE("neighbours8 gives the in-grid neighbours counter-clockwise from the first direction") {
  const GridGeometry g{4, 5, 1.0, 1.0};
  CHECK(dirsAround(g, {1, 1}, 0) == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7});
  CHECK(dirsAround(g, {2, 2}, 3) == std::vector<int>{3, 4, 5, 6, 7, 0, 1, 2});
  CHECK(dirsAround(g, {2, 2}, -2) == std::vector<int>{6, 7, 0, 1, 2, 3, 4, 5});
  CHECK(dirsAround(g, {0, 0}, 0) == std::vector<int>{0, 6, 7});  // E, S, SE
  CHECK(dirsAround(g, {3, 4}, 4) == std::vector<int>{4, 2, 3});  // W, then N, NW
  CHECK(dirsAround(GridGeometry{1, 1, 1.0, 1.0}, {0, 0}, 0).empty());
}

TEST_CASE("neighbourDir names the move to every in-grid neighbour, on the border and on narrow grids") {
  // Every cell of grids 1 to 5 columns wide: the flat-offset answer equals the row/column one.
  for (int cols = 1; cols <= 5; ++cols) {
    const GridGeometry g{4, cols, 1.0, 1.0};
    for (int i = 0; i < g.cellCount(); ++i)
      for (const Neighbour& n : neighbours8(g, i)) CHECK(neighbourDir(g, i, n.index) == n.dir);
  }
}

TEST_CASE("dirOf inverts the direction tables") {
  for (int d = 0; d < kDirections; ++d) CHECK(dirOf(kDirRow[d], kDirCol[d]) == d);
  CHECK(dirOf(0, 0) == -1);
}

TEST_CASE("one rover limit: 1 to kMaxRovers") {
  CHECK_NOTHROW(planning::checkRoverCount(1));
  CHECK_NOTHROW(planning::checkRoverCount(planning::kMaxRovers));
  CHECK_THROWS_WITH_AS(planning::checkRoverCount(0), "between 1 and 64 rovers are supported", Error);
  CHECK_THROWS_AS(planning::checkRoverCount(planning::kMaxRovers + 1), Error);
  const World w = generateWorld({});
  std::vector<StartCell> starts(static_cast<std::size_t>(planning::kMaxRovers) + 1);
  for (std::size_t k = 0; k < starts.size(); ++k) starts[k] = {static_cast<int>(k), 0};
  CHECK_THROWS_AS(runCoverage(w, starts, CoverageParams{}), Error);
}

TEST_CASE("move energy looked up for flat grid moves is paper 000 eq. 5's number") {
  EnergyModel e;
  e.gravity = 3.71;
  const double cell = 0.25;
  const MoveEnergy m(e, cell);
  for (int from = 0; from < 8; ++from)
    for (int to = 0; to < 8; ++to) CHECK(m.turn(from, to) == turnEnergy(e, from, to));
  CHECK(m.forward(cell, 0.0) == forwardEnergy(e, cell, 0.0));
  CHECK(m.forward(cell * std::numbers::sqrt2, -0.0) == forwardEnergy(e, cell * std::numbers::sqrt2, -0.0));
  CHECK(m.forward(cell, 0.1) == forwardEnergy(e, cell, 0.1));
  CHECK(m.forward(0.3, 0.0) == forwardEnergy(e, 0.3, 0.0));
  CHECK(MoveEnergy::pitchDeg(cell, 0.0) == 0.0);
  CHECK(MoveEnergy::pitchDeg(1.0, -1.0) == doctest::Approx(45.0));
}

TEST_CASE("a perfect pose senses every cell within R of every cell it stood in") {
  for (int radius : {1, 2}) {
    WorldParams wp;
    wp.rows = wp.cols = 30;
    wp.obstacleFraction = 0.1;
    wp.seed = 4;
    const World w = generateWorld(wp);
    CoverageParams p;
    p.senseRadius = radius;
    p.mode = TeamMode::Voronoi;
    p.maxSteps = 300;  // stop early: unknown cells remain away from the tracks
    const CoverageResult res = runCoverage(w, randomStarts(w, 2, 9), p);
    const GridGeometry& g = w.geometry();
    int unknown = 0;
    for (CellState s : res.finalStates) unknown += s == CellState::Unknown;
    CHECK(unknown > 0);
    for (const RoverTrack& t : res.rovers)
      for (int cell : t.cells) {
        const CellIndex c = g.cell(cell);
        for (int row = c.row - radius; row <= c.row + radius; ++row)
          for (int col = c.col - radius; col <= c.col + radius; ++col) {
            if (!g.contains(row, col) || res.region[g.index(row, col)] != res.region[cell]) continue;
            const CellState s = res.finalStates[g.index(row, col)];
            CHECK(s != CellState::Unknown);
            CHECK((s == CellState::Obstacle) == w.isObstacle(g.index(row, col)));
          }
      }
  }
}

TEST_CASE("a map counts the unknown cells of its region through every way a cell becomes known") {
  // The perfect plant stops sensing at 0 (nothing left to learn): the count must be exact.
  const GridGeometry g{3, 4, 1.0, 1.0};
  std::vector<std::uint8_t> region(12, 1);
  region[11] = 0;  // one cell belongs to another rover
  KnowledgeMap m(g, region);
  CHECK(m.unknownCells() == 11);
  m.visit(5);  // a start cell, entered before the first sensing
  CHECK(m.unknownCells() == 10);
  m.visit(5);  // a revisit changes nothing
  CHECK(m.unknownCells() == 10);
  CHECK(m.sense(0, true));
  CHECK_FALSE(m.sense(0, false));  // known already
  CHECK(m.unknownCells() == 9);
  const std::uint8_t truth[12] = {1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1};
  int told = 0;
  m.senseLine(8, 1, 4, truth, [&](int, CellState) { ++told; });  // cell 11 is outside the region
  CHECK(told == 3);
  CHECK(m.unknownCells() == 6);
  CHECK(m.markObstacle(1));  // a bump into a cell never sensed
  CHECK(m.markObstacle(5));  // a bump into a visited cell: it was known already
  CHECK(m.unknownCells() == 5);
  for (int i : {2, 3, 4, 6, 7}) m.sense(i, truth[i] != 0);
  CHECK(m.unknownCells() == 0);
  CHECK(m.state(11) == CellState::Unknown);
}

TEST_CASE("reachable cells: all free cells after full coverage, the flood otherwise") {
  const World sealed = test::worldFrom({
      ".....#...",
      ".....#.#.",
      ".....#...",
      "....###..",
      ".........",
  });
  const World pocket = test::worldFrom({
      ".....###.",
      ".....#.#.",
      ".....###.",
      ".........",
  });
  CoverageParams p;
  p.coverage = 1.0;
  const CoverageResult open = runCoverage(sealed, {test::at(sealed, 0, 0, 0)}, p);
  CHECK(open.metrics.visitedCells == open.metrics.freeCells);
  CHECK(open.metrics.reachableCells == open.metrics.freeCells);
  CHECK(open.metrics.unreachableCells == 0);
  p.maxSteps = 500;
  const CoverageResult shut = runCoverage(pocket, {test::at(pocket, 0, 0, 0)}, p);
  CHECK(shut.metrics.unreachableCells == 1);
  CHECK(shut.metrics.reachableCells == shut.metrics.freeCells - 1);
}
