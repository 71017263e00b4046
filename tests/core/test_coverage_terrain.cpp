#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/common/error.hpp"

#include <algorithm>

using namespace rover;
using namespace rover::coverage;

namespace {

// A 60 × 60 m site at 1 m with a conical crater of radius 14 m whose walls slope 13°: steep but
// traversable (below the 15° impassable class), so only the cost function keeps a rover out.
terrain::Dem craterDem() {
  terrain::Dem d;
  d.z = Raster<float>(GridGeometry{60, 60, 1.0, 1.0}, 0.0f);
  const double k = std::tan(13.0 * std::numbers::pi / 180.0);
  for (int r = 0; r < 60; ++r)
    for (int c = 0; c < 60; ++c) {
      Eigen::Vector2d p = cellToLocal(d.geometry(), {r, c});
      double dist = std::hypot(p.x() - 30, p.y() - 30);
      d.z(r, c) = static_cast<float>(dist < 14 ? -k * (14 - dist) : 0.0);
    }
  return d;
}

struct Outcome {
  int innerMoves = 0;  // moves ending within 7 m of the crater centre
  double maxPitchDeg = 0;
  double energyJ = 0;
};

Outcome run(double beta) {
  terrain::Dem dem = craterDem();
  World w = worldFromDem(dem);
  CHECK(w.obstacleCount() == 0);
  CoverageParams p;
  p.pattern = "boustrophedon";
  p.alpha = 1 - beta;
  p.beta = beta;
  p.maxSteps = 300;
  // West of the crater, heading east straight at it.
  auto res = runCoverage(w, {{w.geometry().index(29, 4), 0}}, p);
  Outcome o;
  for (int cell : res.rovers[0].cells) {
    Eigen::Vector2d xy = cellToLocal(w.geometry(), w.geometry().cell(cell));
    o.innerMoves += std::hypot(xy.x() - 30, xy.y() - 30) < 7;
  }
  o.maxPitchDeg = res.metrics.maxPitchDeg;
  o.energyJ = res.metrics.energyJ;
  return o;
}

}  // namespace

TEST_CASE("paper 000 fig. 4: β = 0 drives through the crater, β = 0.7 goes round it") {
  Outcome through = run(0.0), round = run(0.7);
  MESSAGE("β=0: " << through.innerMoves << " inner moves, max pitch " << through.maxPitchDeg
                  << "°, " << through.energyJ << " J; β=0.7: " << round.innerMoves
                  << " inner moves, max pitch " << round.maxPitchDeg << "°, " << round.energyJ << " J");
  CHECK(through.innerMoves > 3 * round.innerMoves);
  CHECK(round.maxPitchDeg < through.maxPitchDeg);
  CHECK(round.energyJ < through.energyJ);
}

TEST_CASE("impassable and nodata DEM cells become obstacles, heights are kept") {
  terrain::Dem d;
  d.z = Raster<float>(GridGeometry{4, 4, 1.0, 1.0}, 0.0f);
  d.z(0, 0) = 5.0f;  // a 5 m step: its cell and its neighbours are impassable (> 15°)
  d.z(3, 3) = NAN;
  World w = worldFromDem(d);
  CHECK(w.isObstacle(w.geometry().index(0, 0)));
  CHECK(w.isObstacle(w.geometry().index(1, 1)));
  CHECK(w.isObstacle(w.geometry().index(3, 3)));
  CHECK_FALSE(w.isObstacle(w.geometry().index(2, 2)));
  CHECK(w.hasHeights());
}

// --- the coverage grid from any DEM (issue 11) ---

namespace {

terrain::Dem rampDem(int rows, int cols, double dx, double dy, double slope) {
  terrain::Dem d;
  d.z = Raster<float>(GridGeometry{rows, cols, dx, dy}, 0.0f);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) d.z(r, c) = static_cast<float>(slope * (c + 0.5) * dx);
  return d;
}

}  // namespace

TEST_CASE("coverage grid: square cells in the local frame on HiRISE-shaped pixels (0.9967 × 1 m)") {
  terrain::Dem d = rampDem(337, 348, 0.9967, 1.0, 0.01);
  CHECK(nativeCoverageCell(d.geometry()) == 1.0);
  World w = worldFromDem(d, 1.0);
  CHECK_NOTHROW(validateWorld(w));  // before: "coverage cells must be square and positive"
  CHECK(w.geometry().cellWidth == 1.0);
  CHECK(w.geometry().cellHeight == 1.0);
  CHECK(w.geometry().rows == 337);
  CHECK(w.geometry().cols == 346);  // 348 × 0.9967 = 346.85 m: the last 0.85 m strip is left out
  CHECK(w.obstacleCount() == 0);
  // Heights: the mean of the pixels whose centres fall in the cell, so the ramp is kept.
  for (int c : {0, 100, 345}) {
    const double x = cellToLocal(w.geometry(), {10, c}).x();
    CHECK(w.heights(10, c) == doctest::Approx(0.01 * x).epsilon(0.01));
  }
}

TEST_CASE("coverage grid: coarser cells average their pixels, one impassable pixel blocks the cell") {
  terrain::Dem d = rampDem(40, 40, 1.0, 1.0, 0.0);
  d.z(5, 6) = 2.0f;  // 63° to its neighbours
  d.z(30, 30) = NAN;
  World w = worldFromDem(d, 4.0);
  REQUIRE(w.geometry().rows == 10);
  REQUIRE(w.geometry().cols == 10);
  CHECK(w.isObstacle(w.geometry().index(1, 1)));  // pixels 4..7: holds (5, 6) and its neighbours
  CHECK(w.isObstacle(w.geometry().index(7, 7)));  // nodata
  CHECK_FALSE(w.isObstacle(w.geometry().index(5, 5)));
  terrain::Dem ramp = rampDem(40, 40, 1.0, 1.0, 0.1);
  World wr = worldFromDem(ramp, 4.0);
  CHECK(wr.heights(3, 2) == doctest::Approx(0.1 * 10.0));  // pixel centres 8.5..11.5 m east
}

TEST_CASE("coverage grid: finer cells than the pixels take the bilinear surface at their centre") {
  terrain::Dem d = rampDem(20, 20, 1.0, 1.0, 0.1);
  World w = worldFromDem(d, 0.5);
  REQUIRE(w.geometry().cols == 40);
  for (int c = 2; c < 38; ++c)
    CHECK(w.heights(7, c) == doctest::Approx(0.1 * cellToLocal(w.geometry(), {7, c}).x()));
}

TEST_CASE("coverage grid: no move between free cells pitches at the impassable slope") {
  // Rough ground: seeded bumps steep enough that averaging alone would let some moves past 15°.
  terrain::Dem d = rampDem(90, 90, 1.0, 1.0, 0.0);
  std::uint64_t s = 12345;
  for (int r = 0; r < 90; ++r)
    for (int c = 0; c < 90; ++c) {
      s = s * 6364136223846793005ULL + 1442695040888963407ULL;
      d.z(r, c) = static_cast<float>(0.4 * static_cast<double>(s >> 40) / (1 << 24));
    }
  for (double cell : {0.7, 1.0, 1.5}) {
    CAPTURE(cell);
    World w = worldFromDem(d, cell);
    CoverageParams p;
    p.frontier = true;
    std::vector<int> sizes;
    auto label = freeComponents(w, sizes);
    REQUIRE_FALSE(sizes.empty());
    const auto largest = std::max_element(sizes.begin(), sizes.end()) - sizes.begin();
    const auto start = static_cast<int>(std::find(label.begin(), label.end(), largest) - label.begin());
    auto res = runCoverage(w, {{start, 0}}, p);
    CHECK(res.metrics.moves > 0);
    CHECK(res.metrics.maxPitchDeg < 15.0 + 1e-3);
  }
}

TEST_CASE("coverage cell defaults: the map's own cell, or the smallest that fits the budget") {
  const GridGeometry hirise{337, 348, 0.9967, 1.0};
  CHECK(defaultCoverageCell(hirise, 400'000) == 1.0);
  const GridGeometry kepler{804, 804, 47.7, 47.7};  // 38 351 m a side
  CHECK(defaultCoverageCell(kepler, 1'000'000) == 47.7);
  const double cell = defaultCoverageCell(kepler, 400'000);
  const GridGeometry g = coverageGrid(kepler, cell);
  CHECK(static_cast<std::int64_t>(g.rows) * g.cols <= 400'000);
  CHECK(cell == doctest::Approx(kepler.widthMetres() / std::sqrt(400'000.0)).epsilon(0.01));
  CHECK(resolveCoverageCell(kepler, 0, 400'000) == cell);
  // Before: the 1 m default asked for 38 351² cells and the map was refused; now only an explicit
  // 1 m is, saying what fits.
  CHECK_THROWS_WITH_AS(resolveCoverageCell(kepler, 1.0, 400'000),
                       doctest::Contains("more than the 1000000 a coverage grid may hold; 47.7 m fits"),
                       Error);
  try {
    resolveCoverageCell(kepler, 50'000, 400'000);
    FAIL("a cell larger than the map was accepted");
  } catch (const Error& e) {
    CHECK(e.field() == "coverage_cell");
    CHECK(std::string(e.what()).find("fewer than 2 × 2 cells") != std::string::npos);
  }
}
