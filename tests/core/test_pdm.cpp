#include <doctest/doctest.h>

#include <cmath>
#include <numeric>

#include "core/common/error.hpp"
#include "core/pdm/pdm.hpp"

using namespace rover;
using namespace rover::pdm;

namespace {
double sum(const Raster<float>& r) {
  double s = 0;
  for (int i = 0; i < r.geometry.cellCount(); ++i) s += r.at(i);
  return s;
}
int argmax(const Raster<float>& r) {
  int best = 0;
  for (int i = 0; i < r.geometry.cellCount(); ++i)
    if (r.at(i) > r.at(best)) best = i;
  return best;
}
Gaussian at(double x, double y, double sx, double sy = -1, double w = 1) {
  Gaussian g;
  g.mean = {x, y};
  g.sigmaX = sx;
  g.sigmaY = sy < 0 ? sx : sy;
  g.weight = w;
  return g;
}
}  // namespace

TEST_CASE("one Gaussian: mass per cell sums to 1 and peaks at the mean") {
  GridGeometry g{50, 40, 1.0, 1.0};
  Raster<float> p = discretise({at(10.5, 30.5, 3.0)}, g);
  CHECK(sum(p) == doctest::Approx(1.0).epsilon(1e-5));
  CHECK(g.cell(argmax(p)) == *localToCell(g, {10.5, 30.5}));
  // Mass of the centre cell ≈ density × area = 1/(2π σ²).
  CHECK(p.at(argmax(p)) == doctest::Approx(1.0 / (2 * std::numbers::pi * 9.0)).epsilon(0.01));
}

TEST_CASE("equal components share the mass (paper 001 eq. 5: 1/G Σ N), weights tilt it") {
  GridGeometry g{20, 60, 1.0, 1.0};
  auto massNear = [&](const Raster<float>& p, double x) {
    double m = 0;
    for (int r = 0; r < g.rows; ++r)
      for (int c = 0; c < g.cols; ++c)
        if (std::fabs(cellToLocal(g, {r, c}).x() - x) < 15) m += p(r, c);
    return m;
  };
  Raster<float> even = discretise({at(15, 10, 2), at(45, 10, 2)}, g);
  CHECK(massNear(even, 15) == doctest::Approx(0.5).epsilon(1e-3));
  Raster<float> tilted = discretise({at(15, 10, 2, -1, 3), at(45, 10, 2, -1, 1)}, g);
  CHECK(massNear(tilted, 15) == doctest::Approx(0.75).epsilon(1e-3));
}

TEST_CASE("rotation turns the long axis") {
  GridGeometry g{60, 60, 1.0, 1.0};
  Gaussian e = at(30, 30, 10, 2);
  Raster<float> flat = discretise({e}, g);
  e.rotation = std::numbers::pi / 2;
  Raster<float> upright = discretise({e}, g);
  // Along x the un-rotated one spreads; rotated by 90° it spreads along y.
  CHECK(flat(30, 45) > 10 * flat(15, 30));
  CHECK(upright(15, 30) > 10 * upright(30, 45));
}

TEST_CASE("nodata cells get no mass; the rest is renormalised") {
  GridGeometry g{10, 10, 1.0, 1.0};
  std::vector<std::uint8_t> valid(100, 1);
  for (int c = 0; c < 10; ++c) valid[g.index(4, c)] = 0;
  Raster<float> p = discretise({at(5, 5, 2)}, g, valid);
  CHECK(p(4, 3) == 0.0f);
  CHECK(sum(p) == doctest::Approx(1.0).epsilon(1e-5));
  std::vector<std::uint8_t> none(100, 0);
  CHECK_THROWS_WITH_AS(discretise({at(5, 5, 2)}, g, none),
                       "no probability mass falls on valid cells of the map", Error);
}

TEST_CASE("a component narrower than a cell is still integrated, not missed between centres") {
  GridGeometry g{10, 10, 1.0, 1.0};
  Raster<float> p = discretise({at(5.0, 5.0, 0.05)}, g);  // on a cell corner
  CHECK(sum(p) == doctest::Approx(1.0).epsilon(1e-5));
  // The four cells meeting at the corner share the mass.
  CHECK(p(4, 4) == doctest::Approx(0.25).epsilon(0.02));
  CHECK(p(5, 5) == doctest::Approx(0.25).epsilon(0.02));
}

TEST_CASE("bad components name their field") {
  GridGeometry g{10, 10, 1.0, 1.0};
  CHECK_THROWS_WITH_AS(discretise({}, g), "components: at least one Gaussian component is needed", Error);
  CHECK_THROWS_WITH_AS(discretise({at(1, 1, 1), at(2, 2, 0)}, g),
                       "components[1].sigma_x: must be a positive number of metres", Error);
  CHECK_THROWS_WITH_AS(discretise({at(1, 1, 1, 1, -2)}, g),
                       "components[0].weight: must be a finite number >= 0", Error);
  CHECK_THROWS_WITH_AS(discretise({at(1, 1, 1, 1, 0)}, g), "components: the weights sum to 0", Error);
}

TEST_CASE("random PDMs: G components inside the map, seeded") {
  GridGeometry g{600, 600, 0.25, 0.25};
  auto a = randomGaussians(g, 4, 9), b = randomGaussians(g, 4, 9), c = randomGaussians(g, 4, 10);
  REQUIRE(a.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {
    CHECK(a[i].mean == b[i].mean);
    CHECK(a[i].mean.x() >= 0);
    CHECK(a[i].mean.x() <= 150);
    CHECK(a[i].sigmaX >= 0.05 * 150);
    CHECK(a[i].sigmaX <= 0.20 * 150);
  }
  CHECK(a[0].mean != c[0].mean);
  CHECK(sum(discretise(a, g)) == doctest::Approx(1.0).epsilon(1e-4));
}

TEST_CASE("raster PDMs are normalised; negative or infinite weights are rejected") {
  Raster<float> w(GridGeometry{2, 2, 1, 1}, 1.0f);
  w(0, 0) = 3.0f;
  w(1, 1) = NAN;
  Raster<float> p = normaliseWeights(w);
  CHECK(p(0, 0) == doctest::Approx(0.6));
  CHECK(p(1, 1) == 0.0f);
  w(0, 1) = -1;
  CHECK_THROWS_WITH_AS(normaliseWeights(w), "PDM raster values must be finite and >= 0", Error);
  Raster<float> zero(GridGeometry{2, 2, 1, 1}, 0.0f);
  CHECK_THROWS_WITH_AS(normaliseWeights(zero), "the PDM raster sums to 0 on the map", Error);
}
