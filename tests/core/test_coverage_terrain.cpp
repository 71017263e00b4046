#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/terrain_world.hpp"

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

TEST_CASE("impassable and nodata DEM cells become obstacles; heights are kept") {
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
