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

TEST_CASE("nodata cells get no mass, the rest is renormalised") {
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

TEST_CASE("raster PDMs are normalised, negative or infinite weights are rejected") {
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

namespace {
// The discretisation as it was before the ellipse window (every cell of the ±6σ box), kept here
// as the reference the windowed one must reproduce.
std::vector<double> boxReference(const std::vector<Gaussian>& cs, const GridGeometry& g) {
  std::vector<double> mass(g.cellCount(), 0.0);
  double wTotal = 0;
  for (const auto& c : cs) wTotal += c.weight;
  for (const auto& gs : cs) {
    const double co = std::cos(gs.rotation), si = std::sin(gs.rotation);
    const double ix = 1.0 / (gs.sigmaX * gs.sigmaX), iy = 1.0 / (gs.sigmaY * gs.sigmaY);
    const double A = co * co * ix + si * si * iy, B = co * si * (ix - iy), C = si * si * ix + co * co * iy;
    const double norm = 1.0 / (2.0 * std::numbers::pi * gs.sigmaX * gs.sigmaY);
    const double reach = 6.0 * std::max(gs.sigmaX, gs.sigmaY);
    const int s = std::clamp(static_cast<int>(std::ceil(2.0 * std::max(g.cellWidth, g.cellHeight) /
                                                        std::min(gs.sigmaX, gs.sigmaY))), 1, 16);
    const int c0 = std::max(0, static_cast<int>(std::floor((gs.mean.x() - reach) / g.cellWidth)));
    const int c1 = std::min(g.cols - 1, static_cast<int>(std::floor((gs.mean.x() + reach) / g.cellWidth)));
    const int r0 = std::max(0, g.rows - 1 - static_cast<int>(std::floor((gs.mean.y() + reach) / g.cellHeight)));
    const int r1 = std::min(g.rows - 1, g.rows - 1 - static_cast<int>(std::floor((gs.mean.y() - reach) / g.cellHeight)));
    const double wNorm = gs.weight / wTotal * norm * g.cellWidth * g.cellHeight / (s * s);
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        double sum = 0;
        for (int a = 0; a < s; ++a) {
          const double y = (g.rows - r - (a + 0.5) / s) * g.cellHeight - gs.mean.y();
          for (int b = 0; b < s; ++b) {
            const double x = (c + (b + 0.5) / s) * g.cellWidth - gs.mean.x();
            sum += std::exp(-0.5 * (A * x * x + 2 * B * x * y + C * y * y));
          }
        }
        mass[g.index(r, c)] += wNorm * sum;
      }
  }
  double total = 0;
  for (double m : mass) total += m;
  for (double& m : mass) m /= total;
  return mass;
}

// Largest difference relative to each cell's own reference mass, over the cells holding at least
// 1e-9 of the peak (below that float32 output itself has no relative precision to compare), and
// the summed absolute difference over all cells.
std::pair<double, double> compare(const Raster<float>& got, const std::vector<double>& want) {
  double peak = 0, worstRel = 0, l1 = 0;
  for (double w : want) peak = std::max(peak, w);
  for (std::size_t i = 0; i < want.size(); ++i) {
    const double d = std::fabs(static_cast<double>(got.at(static_cast<int>(i))) - want[i]);
    l1 += d;
    if (want[i] >= 1e-9 * peak) worstRel = std::max(worstRel, d / want[i]);
  }
  return {worstRel, l1};
}
}  // namespace

TEST_CASE("the ellipse window reproduces the whole-box integration within 1e-6 (float output)") {
  // Normal inputs: the paper's random G = 4 on several grids, hand-made rotated and elongated
  // ones, a sub-cell one, and one near the edge.
  std::vector<std::pair<GridGeometry, std::vector<Gaussian>>> inputs;
  for (std::uint64_t seed : {1, 2, 3}) {
    GridGeometry g{120, 150, 1.0, 1.0};
    inputs.push_back({g, randomGaussians(g, 4, seed)});
  }
  GridGeometry g2{80, 60, 0.5, 0.5};
  Gaussian e = at(12, 20, 6, 1.5, 2);
  e.rotation = 0.7;
  Gaussian f = at(25, 35, 0.3, 0.3);
  Gaussian h = at(1, 39, 4, 9);
  h.rotation = -2.1;
  inputs.push_back({g2, {e, f, h}});
  Gaussian thin = at(30, 20, 40, 0.4);
  thin.rotation = std::numbers::pi / 4;
  inputs.push_back({g2, {thin, at(10, 10, 3)}});
  for (const auto& input : inputs) {
    // Named members, not a structured binding: clang 14 cannot capture one in CAPTURE's lambda.
    const GridGeometry& g = input.first;
    const auto& cs = input.second;
    auto [rel, l1] = compare(discretise(cs, g), boxReference(cs, g));
    CAPTURE(g.rows);
    MESSAGE("window vs box: worst relative difference ", rel, ", summed absolute ", l1);
    // float32 rounding is ~6e-8 relative; the window drops only samples below e^-32 of a peak.
    CHECK(rel < 1e-6);
    CHECK(l1 < 1e-6);
  }
}

TEST_CASE("a long thin rotated component costs its own cells, not its box") {
  // σ 2e4 m × 1 mm rotated 45° over a 600 × 600 map: all the mass lies on the diagonal cells.
  GridGeometry g{600, 600, 0.25, 0.25};
  Gaussian thin = at(75, 75, 2e4, 1e-3);
  thin.rotation = std::numbers::pi / 4;
  Raster<float> p = discretise({thin}, g);
  CHECK(sum(p) == doctest::Approx(1.0).epsilon(1e-5));
  int nonzero = 0;
  for (int i = 0; i < g.cellCount(); ++i) nonzero += p.at(i) > 0;
  CHECK(nonzero > 600);
  CHECK(nonzero < 3 * 600);
}

TEST_CASE("PDM bounds relative to the map name their field") {
  GridGeometry g{100, 100, 1.0, 1.0};  // 100 m square, diagonal 141 m
  auto fieldOf = [&](Gaussian c) {
    try {
      validateGaussians({at(50, 50, 5), c}, g);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string();
  };
  CHECK(fieldOf(at(50, 1e30, 5)) == "components[1].y");
  CHECK(fieldOf(at(-200, 50, 5)) == "components[1].x");
  CHECK(fieldOf(at(240, 50, 5)).empty());  // within one diagonal of the map
  CHECK(fieldOf(at(50, 50, 1e-300)) == "components[1].sigma_x");
  CHECK(fieldOf(at(50, 50, 5, 1e300)) == "components[1].sigma_y");
  CHECK(fieldOf(at(50, 50, 5, 5, 1e300)) == "components[1].weight");
  CHECK(fieldOf(at(50, 50, 2e-3)).empty());
  std::vector<Gaussian> many(kMaxComponents + 1, at(50, 50, 5));
  CHECK_THROWS_WITH_AS(validateGaussians(many, g), "components: at most 256 components", Error);
  CHECK_THROWS_AS(randomGaussians(g, 257, 1), Error);
  // A mean far outside a tiny map does not overflow anything: it is refused by name.
  CHECK_THROWS_WITH_AS(discretise({at(1e15, 1, 1)}, g), doctest::Contains("components[0].x"), Error);
}

TEST_CASE("pdm: the work is bounded before any is done (issue 14: two PDM requests held the work pool 8 min)") {
  // A 7000² map (49 M cells): one component as wide as the map costs one evaluation a cell…
  const GridGeometry g{7000, 7000, 1.0, 1.0};
  pdm::Gaussian wide;
  wide.mean = {3500, 3500};
  wide.sigmaX = wide.sigmaY = 50.0 * 7000;
  const double one = pdm::discretisationCost({wide}, g);
  CHECK(one == doctest::Approx(double(g.cellCount())));
  // …so 256 of them (the attack: 12.5 G evaluations) are refused by discretise at once, naming
  // the field, without allocating or computing anything.
  std::vector<pdm::Gaussian> many(256, wide);
  CHECK(pdm::discretisationCost(many, g) > pdm::kMaxDiscretisationSamples);
  try {
    pdm::discretise(many, g);
    FAIL("accepted");
  } catch (const Error& e) {
    CHECK(e.field() == "components");
    CHECK(std::string(e.what()).find("density evaluations") != std::string::npos);
  }
  // The cost counts only the cells a component's window meets: a narrow one in a corner is cheap.
  pdm::Gaussian narrow;
  narrow.mean = {10, 10};
  narrow.sigmaX = narrow.sigmaY = 2.0;
  const double small = pdm::discretisationCost({narrow}, g);
  CHECK(small > 0);
  CHECK(small < 40 * 40 * 16);
}
