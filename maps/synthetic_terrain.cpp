#include "maps/synthetic_terrain.hpp"

#include <cpl_conv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/common/error.hpp"
#include "core/common/random.hpp"

// How the terrain is built, and why.
//
// Everything is laid out in the local frame (x east, y north, metres from the lower-left corner,
// SPEC §0) at cell centres, so a feature is the same physical object whatever the grid. Features
// are added in geological order: rolling relief (and, on Mars, a ridge field) first, then craters
// from oldest to youngest, each young crater erasing what lay inside its bowl, then loose rocks on
// top. All randomness comes from rover::Rng streams derived from the one seed (core/common/
// random.hpp), never from std:: distributions, so a seed gives the same heights on every standard
// library; the libm functions used (pow, sqrt, exp, cos, sin) give the same bits on one build.
//
// Scale. Relief is fractal (amplitude ∝ wavelength^H with H < 1, so slopes fall gently with
// baseline, as measured on planetary DTMs); craters follow a cumulative power law N(>D) ∝ D^-2,
// which is itself scale-free. Both are cut at the small end where the grid can no longer draw them
// (a few cells), so a coarse grid of a large site shows the same slope statistics as a fine grid of
// a small one, and a large site simply holds more and bigger craters. Rocks have a physical size
// (0.2–1.5 m); those smaller than a cell are left out, so on a 10 m grid there are none.
//
// Tuning target (SPEC §2, paper 001 §3.4 classes on the worst 8-neighbour slope): on the defaults
// (600 × 600 cells of 0.25 m) roughly 80–95 % traversable (< 10°), 3–15 % high risk and 1–8 %
// impassable (≥ 15°); their Jezero site had 89.5 / 8.4 / 2.1 %. The impassable share sits in
// crater walls, ridge crests and rocks rather than everywhere.
// tests/maps/test_synthetic_terrain.cpp checks those ranges.

namespace rover::maps {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Sub-seed streams (rover::deriveSeed), one per feature, so changing one never shifts another.
enum Stream : std::uint64_t { kReliefStream = 1, kRidgeStream, kCraterStream, kRockStream };

// ----------------------------------------------------------------------------------------------
// Gradient noise (Perlin 2002, "Improving noise": quintic fade, gradients at integer lattice
// points). The gradient of a lattice point comes from a hash of (seed, i, j), so there is no
// permutation table and no period.

std::uint64_t latticeHash(std::uint64_t seed, std::int64_t i, std::int64_t j) {
  std::uint64_t h = seed ^ (static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull);
  h ^= static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full;
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;  // SplitMix64 finaliser
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

// 16 unit vectors at 22.5° steps, written out so that no libm call is involved.
constexpr double kGradients[16][2] = {
    {1.0, 0.0},
    {0.9238795325112867, 0.3826834323650898},
    {0.7071067811865476, 0.7071067811865476},
    {0.3826834323650898, 0.9238795325112867},
    {0.0, 1.0},
    {-0.3826834323650898, 0.9238795325112867},
    {-0.7071067811865476, 0.7071067811865476},
    {-0.9238795325112867, 0.3826834323650898},
    {-1.0, 0.0},
    {-0.9238795325112867, -0.3826834323650898},
    {-0.7071067811865476, -0.7071067811865476},
    {-0.3826834323650898, -0.9238795325112867},
    {0.0, -1.0},
    {0.3826834323650898, -0.9238795325112867},
    {0.7071067811865476, -0.7071067811865476},
    {0.9238795325112867, -0.3826834323650898},
};

double fade(double t) {
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// One layer of noise: wavelength in metres and a random lattice offset, so that octaves of one
// seed are unrelated.
struct NoiseLayer {
  std::uint64_t seed = 0;
  double wavelength = 1.0;
  double offsetX = 0.0;  // lattice units
  double offsetY = 0.0;

  static NoiseLayer make(std::uint64_t seed, double wavelength) {
    Rng rng(seed);
    NoiseLayer layer;
    layer.seed = rng.next();
    layer.wavelength = wavelength;
    layer.offsetX = 1024.0 * rng.uniform();
    layer.offsetY = 1024.0 * rng.uniform();
    return layer;
  }
};

// out[k] += amplitude · n(x0 + k·dx, y) for k in [0, count), n in about [-1, 1]. Works a row at a
// time so the four corner gradients are fetched only when the lattice cell changes (the cost per
// cell is then a handful of multiplications, which keeps 4096² grids fast).
void addNoiseRow(const NoiseLayer& layer, double amplitude, double y, double x0, double dx,
                 int count, double* out) {
  const double scale = amplitude * std::sqrt(2.0);  // 2-D Perlin noise peaks at ±√2/2
  const double invWavelength = 1.0 / layer.wavelength;
  const double v = y * invWavelength + layer.offsetY;
  const double jf = std::floor(v);
  const auto j = static_cast<std::int64_t>(jf);
  const double fy = v - jf;
  const double sy = fade(fy);
  const double u0 = x0 * invWavelength + layer.offsetX;
  const double du = dx * invWavelength;
  // u grows along the row, so the row splits into spans of cells inside one lattice cell; within
  // a span the gradients are fixed and the loop has no branch (the compiler vectorises it).
  for (int k = 0; k < count;) {
    const double iF = std::floor(u0 + k * du);
    const auto i = static_cast<std::int64_t>(iF);
    const double guess = std::clamp((iF + 1.0 - u0) / du - k, 0.0, static_cast<double>(count));
    int end = std::min(count, k + 1 + static_cast<int>(guess));
    while (end > k + 1 && u0 + (end - 1) * du - iF >= 1.0) --end;
    while (end < count && u0 + end * du - iF < 1.0) ++end;
    const double* a = kGradients[latticeHash(layer.seed, i, j) & 15u];
    const double* b = kGradients[latticeHash(layer.seed, i + 1, j) & 15u];
    const double* c = kGradients[latticeHash(layer.seed, i, j + 1) & 15u];
    const double* d = kGradients[latticeHash(layer.seed, i + 1, j + 1) & 15u];
    const double g00x = a[0], g00y = a[1], g10x = b[0], g10y = b[1];
    const double g01x = c[0], g01y = c[1], g11x = d[0], g11y = d[1];
    for (; k < end; ++k) {
      const double fx = u0 + k * du - iF;
      const double sx = fade(fx);
      const double n00 = g00x * fx + g00y * fy;
      const double n10 = g10x * (fx - 1.0) + g10y * fy;
      const double n01 = g01x * fx + g01y * (fy - 1.0);
      const double n11 = g11x * (fx - 1.0) + g11y * (fy - 1.0);
      const double bottom = n00 + sx * (n10 - n00);
      const double top = n01 + sx * (n11 - n01);
      out[k] += scale * (bottom + sy * (top - bottom));
    }
  }
}

// ----------------------------------------------------------------------------------------------
// The grid in the local frame.

struct Canvas {
  RowMajorMatrix<float>& z;
  int n = 0;
  double cell = 1.0;

  double extent() const { return n * cell; }
  double x(int col) const { return (col + 0.5) * cell; }
  double y(int row) const { return (n - row - 0.5) * cell; }
  // Cells whose centres lie within [x0, x1] × [y0, y1], clipped to the grid; empty when outside.
  struct Box {
    int row0, row1, col0, col1;
    bool empty() const { return row0 > row1 || col0 > col1; }
  };
  Box box(double x0, double x1, double y0, double y1) const {
    auto clampIndex = [this](double v) {
      return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(n)));
    };
    return {std::max(0, clampIndex(std::ceil(n - 0.5 - y1 / cell))),
            std::min(n - 1, clampIndex(std::floor(n - 0.5 - y0 / cell))),
            std::max(0, clampIndex(std::ceil(x0 / cell - 0.5))),
            std::min(n - 1, clampIndex(std::floor(x1 / cell - 0.5)))};
  }
  // Height at the cell nearest to (x, y), clamped into the grid.
  double heightNear(double px, double py) const {
    const double last = n - 1.0;
    const auto col = static_cast<int>(std::clamp(std::floor(px / cell), 0.0, last));
    const auto row = static_cast<int>(std::clamp(std::floor(n - py / cell), 0.0, last));
    return z(row, col);
  }
};

// ----------------------------------------------------------------------------------------------
// Rolling relief: fractional Brownian motion from octaves of gradient noise. An octave of
// wavelength λ gets amplitude A(λ) = s·λ/(2π)·(λ/λref)^(H−1): its slopes are ~s at λref and fall
// as λ^(H−1) at longer wavelengths (H ≈ 0.7–0.9 for planetary surfaces at metre to km baselines,
// e.g. Kreslavsky & Head 2000 for Mars, Rosenburg et al. 2011 for the Moon).

struct ReliefSpec {
  double slope = 0.0;                 // s, dimensionless, at the reference wavelength
  double hurst = 0.8;                 // H
  double referenceWavelength = 10.0;  // λref, metres
  double maxWavelengthFactor = 1.0;   // longest octave = factor × site extent
  double minWavelength = 1.0;         // metres; never below kMinNoiseCells cells either
  // Rough patches (outcrops, blocky ground among smooth regolith): the shortest `roughOctaves`
  // octaves get their amplitude multiplied by 1 + roughGain·mask, mask a smoothstep of a noise of
  // wavelength patchWavelength (at least 6× the roughest octave) between patchThreshold and
  // patchThreshold + patchRamp. They hold the high-risk ground in patches, not everywhere.
  double roughGain = 0.0;
  int roughOctaves = 2;
  double patchWavelength = 40.0;
  double patchThreshold = 0.2;
  double patchRamp = 0.3;
};

constexpr double kMinNoiseCells = 8.0;  // shorter octaves would be aliased by the grid
constexpr double kLacunarity = 1.93;    // not 2, so octave lattices never line up

double smoothstep01(double t) {
  if (t <= 0) return 0.0;
  if (t >= 1) return 1.0;
  return t * t * (3 - 2 * t);
}

void addRelief(Canvas& canvas, const ReliefSpec& spec, double multiplier, std::uint64_t seed) {
  if (!(spec.slope * multiplier > 0)) return;
  const double shortest = std::max(spec.minWavelength, kMinNoiseCells * canvas.cell);
  struct Octave {
    NoiseLayer layer;
    double amplitude;
  };
  std::vector<Octave> octaves;
  Rng rng(seed);
  // From the site's extent down to the shortest wavelength; a site smaller than that gets one
  // octave at the shortest wavelength (a gentle tilt), not an ever steeper sub-metre one.
  for (double lambda = std::max(spec.maxWavelengthFactor * canvas.extent(), shortest);
       lambda >= shortest || octaves.empty(); lambda /= kLacunarity) {
    const double amplitude = multiplier * spec.slope * lambda / (2 * kPi) *
                             std::pow(lambda / spec.referenceWavelength, spec.hurst - 1.0);
    octaves.push_back({NoiseLayer::make(rng.next(), lambda), amplitude});
    if (lambda < shortest) break;
  }
  const std::size_t rough =
      spec.roughGain > 0 ? std::min<std::size_t>(spec.roughOctaves, octaves.size()) : 0;
  const std::size_t smooth = octaves.size() - rough;
  const NoiseLayer patches = NoiseLayer::make(
      rng.next(),
      std::max(spec.patchWavelength, rough ? 6.0 * octaves[smooth].layer.wavelength : 0.0));
  std::vector<double> row(canvas.n), roughRow(canvas.n), maskRow(canvas.n);
  for (int r = 0; r < canvas.n; ++r) {
    const double y = canvas.y(r);
    std::fill(row.begin(), row.end(), 0.0);
    for (std::size_t k = 0; k < smooth; ++k)
      addNoiseRow(octaves[k].layer, octaves[k].amplitude, y, canvas.x(0), canvas.cell, canvas.n,
                  row.data());
    if (rough > 0) {
      std::fill(roughRow.begin(), roughRow.end(), 0.0);
      std::fill(maskRow.begin(), maskRow.end(), 0.0);
      for (std::size_t k = smooth; k < octaves.size(); ++k)
        addNoiseRow(octaves[k].layer, octaves[k].amplitude, y, canvas.x(0), canvas.cell, canvas.n,
                    roughRow.data());
      addNoiseRow(patches, 1.0, y, canvas.x(0), canvas.cell, canvas.n, maskRow.data());
      for (int c = 0; c < canvas.n; ++c) {
        const double m = smoothstep01((maskRow[c] - spec.patchThreshold) / spec.patchRamp);
        row[c] += roughRow[c] * (1.0 + spec.roughGain * m);
      }
    }
    for (int c = 0; c < canvas.n; ++c) canvas.z(r, c) += static_cast<float>(row[c]);
  }
}

// ----------------------------------------------------------------------------------------------
// Ridge field (Mars): parallel, sharp-crested ridges like the transverse aeolian ridges and
// megaripples of Jezero and Gale — wavelengths of ~10 m, heights of a metre or less, a steeper lee
// side. The cross-section over one wavelength rises as u^γ on each side of the crest (u = 0 in the
// trough, 1 at the crest): flat troughs and steep flanks only near the crest, so the impassable
// cells form thin lines along the crests instead of whole flanks. The crest lines wander (phase
// noise), the height varies along them, and the field covers only part of the site (a smooth
// noise mask), as dune fields do.

struct RidgeSpec {
  bool enabled = false;
  double minWavelength = 8.0;     // metres, drawn uniformly in [min, max] ...
  double maxWavelength = 14.0;    // ... and never below kMinRidgeCells cells
  double aspect = 0.04;           // crest height / wavelength
  int sharpness = 3;              // γ (an integer: u^γ by multiplication)
  double waviness = 0.35;         // crest displacement amplitude, in wavelengths
  double coverThreshold = -0.15;  // mask noise level where the field starts ...
  double coverRamp = 0.35;        // ... and the width of its ramp to full height
};

constexpr double kMinRidgeCells = 12.0;

void addRidges(Canvas& canvas, const RidgeSpec& spec, double multiplier, std::uint64_t seed) {
  if (!spec.enabled || !(multiplier > 0)) return;
  Rng rng(seed);
  const double angle = 2 * kPi * rng.uniform();
  const double cosA = std::cos(angle), sinA = std::sin(angle);
  const double wavelength =
      std::max(spec.minWavelength + (spec.maxWavelength - spec.minWavelength) * rng.uniform(),
               kMinRidgeCells * canvas.cell);
  const double crest = 0.6 + 0.15 * rng.uniform();  // fraction of the wavelength on the stoss side
  const double phase = rng.uniform();
  const double height = multiplier * spec.aspect * wavelength;
  const NoiseLayer mask = NoiseLayer::make(rng.next(), 8.0 * wavelength);
  const NoiseLayer wander = NoiseLayer::make(rng.next(), 4.0 * wavelength);
  const NoiseLayer swell = NoiseLayer::make(rng.next(), 3.0 * wavelength);

  const int n = canvas.n;
  std::vector<double> maskRow(n), wanderRow(n), swellRow(n);
  for (int r = 0; r < n; ++r) {
    const double y = canvas.y(r);
    std::fill(maskRow.begin(), maskRow.end(), 0.0);
    std::fill(wanderRow.begin(), wanderRow.end(), 0.0);
    std::fill(swellRow.begin(), swellRow.end(), 0.0);
    addNoiseRow(mask, 1.0, y, canvas.x(0), canvas.cell, n, maskRow.data());
    addNoiseRow(wander, spec.waviness * wavelength, y, canvas.x(0), canvas.cell, n,
                wanderRow.data());
    addNoiseRow(swell, 1.0, y, canvas.x(0), canvas.cell, n, swellRow.data());
    for (int c = 0; c < n; ++c) {
      const double m = smoothstep01((maskRow[c] - spec.coverThreshold) / spec.coverRamp);
      if (m <= 0) continue;
      const double s = (canvas.x(c) * cosA + y * sinA + wanderRow[c]) / wavelength + phase;
      const double p = s - std::floor(s);
      const double u = p < crest ? p / crest : (1.0 - p) / (1.0 - crest);
      double shape = 1.0;
      for (int k = 0; k < spec.sharpness; ++k) shape *= u;
      const double local = height * m * (0.7 + 0.3 * swellRow[c]);
      canvas.z(r, c) += static_cast<float>(local * shape);
    }
  }
}

// ----------------------------------------------------------------------------------------------
// Craters.
//
// Size-frequency: cumulative N(>D) = K·D^-2 per unit area (D and area in the same unit, so K is
// dimensionless). K ≈ 10^-1.1 ≈ 0.08 is the empirical equilibrium density of small lunar craters
// (Trask 1966; Gault 1970), reached on mare surfaces for D below ~100 m; the geometric saturation
// limit is K ≈ 1.54.
//
// Profile of a fresh simple crater (Pike 1977, lunar simple craters): rim-to-floor depth
// d ≈ 0.196·D, rim height above the surroundings h_r ≈ 0.036·D. The bowl is a paraboloid
// (the usual approximation of a simple crater's cross-section), h(r) = h_r − d·(1 − ρ²) for
// ρ = r/R ≤ 1, relative to the pre-impact surface. Outside, the ejecta blanket thins as h_r·ρ^-3
// (McGetchin, Settle & Head 1973), tapered to zero at ρ = kEjectaRadius. Large craters become
// complex and shallower: depth is capped by the complex-crater law (Pike 1977 for the Moon, d
// = 1.044·D^0.301 km; Garvin et al. 2003 for Mars, d ≈ 0.36·D^0.49 km).
//
// Degradation: most small craters are old and shallowed by diffusion (Fassett & Thomson 2014), so
// each crater gets a uniform age in [0, 1) and a freshness f = exp(−age/τ): diffusion shallows a
// bowl roughly exponentially in time (Fassett & Thomson 2014), and a small τ means that only the
// youngest few percent are still sharp, as in an equilibrium population. f scales d/D from
// kDegradedDepthRatio (f = 0) to the fresh value (f = 1). Craters are stamped oldest first; inside
// its bowl a crater replaces the older topography by its own bowl in proportion to its freshness
// (a fresh crater erases what was there, a degraded one only dents it), and outside it adds its
// ejecta.

struct CraterSpec {
  double density = 0.0;            // K
  double minCells = 4.0;           // smallest D in cells (a smaller bowl is not drawn by the grid)
  double minDiameter = 0.0;        // and in metres
  double maxDiameterFactor = 1.0;  // largest D = factor × site extent ...
  double maxDiameter = 2.0e5;      // ... and never above this (metres)
  // Above breakDiameter the cumulative law steepens to D^-largeSlope: the production population,
  // not yet in equilibrium (lunar maria: equilibrium up to a few hundred metres, production slope
  // about −3 above; Neukum, Ivanov & Hartmann 2001). Keeps a 10 km site from being all basin.
  double breakDiameter = 1.0e30;
  double largeSlope = 3.0;
  double freshnessTime = 0.2;  // τ, as a fraction of the oldest age: smaller = fewer fresh
  // Complex-crater depth d = a·D_km^b km, caps the simple-crater depth for large D.
  double complexDepthA = 1.044;
  double complexDepthB = 0.301;
};

constexpr double kFreshDepthRatio = 0.196;     // Pike 1977
constexpr double kRimToDepth = 0.036 / 0.196;  // Pike 1977, h_r / d
constexpr double kDegradedDepthRatio = 0.035;  // a heavily degraded, shallow crater
constexpr double kEjectaRadius = 2.5;          // in crater radii, where the ejecta taper ends

struct Crater {
  double x = 0, y = 0;      // centre, local metres
  double radius = 0;        // R = D/2
  double depth = 0;         // d, rim crest to floor
  double rim = 0;           // h_r
  double freshness = 0;     // f in [0, 1]
  double age = 0;           // sort key, oldest first
  std::uint64_t order = 0;  // tie-break, keeps the sort deterministic
};

double freshCraterDepth(const CraterSpec& spec, double diameter) {
  const double simple = kFreshDepthRatio * diameter;
  const double complex =
      1000.0 * spec.complexDepthA * std::pow(diameter / 1000.0, spec.complexDepthB);
  return std::min(simple, complex);
}

std::vector<Crater> sampleCraters(const Canvas& canvas, const CraterSpec& spec, double multiplier,
                                  std::uint64_t seed) {
  std::vector<Crater> craters;
  const double k = spec.density * multiplier;
  if (!(k > 0)) return craters;
  const double extent = canvas.extent();
  const double dMin = std::max(spec.minCells * canvas.cell, spec.minDiameter);
  const double dMax = std::min(spec.maxDiameterFactor * extent, spec.maxDiameter);
  if (!(dMax > dMin)) return craters;
  Rng rng(seed);
  // Diameters are handled in units of dMin (δ = D / dMin), so that the powers stay finite for
  // any cell size the validation lets through.
  const double dBreak = spec.breakDiameter / dMin;
  // N(>δ·dMin) per dMin² of area: k·δ^-2 below the break.
  auto cumulative = [&](double d) {
    return d <= dBreak ? k / (d * d)
                       : k / (dBreak * dBreak) * std::pow(d / dBreak, -spec.largeSlope);
  };
  // Octave bins of diameter (split at the break, so each bin follows one power law). Centres
  // fall in the site grown by the ejecta radius of the bin's largest crater, so craters just
  // outside still reach in and the edges are not under-cratered. The count of a bin is its
  // expectation rounded up or down at random (same mean as a Poisson draw, needs no
  // libm-dependent sampling).
  const double top = dMax / dMin;
  for (double d1 = 1.0, d2 = 0; d1 < top; d1 = d2) {
    d2 = std::min(2.0 * d1, top);
    if (d1 < dBreak && d2 > dBreak) d2 = dBreak;
    const double slope = d1 < dBreak ? 2.0 : spec.largeSlope;
    const double margin = kEjectaRadius * d2 * dMin / 2.0;
    const double side = extent + 2 * margin;
    const double expected = (cumulative(d1) - cumulative(d2)) * (side / dMin) * (side / dMin);
    const double a1 = std::pow(d1, -slope), a2 = std::pow(d2, -slope);
    const auto count = static_cast<std::uint64_t>(std::floor(expected + rng.uniform()));
    for (std::uint64_t i = 0; i < count; ++i) {
      Crater c;
      // Inverse CDF of N(>D) ∝ D^-slope truncated to [d1, d2].
      const double diameter = dMin * std::pow(a1 - rng.uniform() * (a1 - a2), -1.0 / slope);
      c.x = -margin + side * rng.uniform();
      c.y = -margin + side * rng.uniform();
      c.radius = diameter / 2.0;
      c.age = rng.uniform();
      c.freshness = std::exp(-c.age / spec.freshnessTime);
      const double ratio =
          kDegradedDepthRatio +
          c.freshness * (freshCraterDepth(spec, diameter) / diameter - kDegradedDepthRatio);
      c.depth = std::max(ratio, 0.0) * diameter;
      c.rim = kRimToDepth * c.depth;
      c.order = craters.size();
      const double reach = kEjectaRadius * c.radius;
      if (c.x + reach < 0 || c.x - reach > extent || c.y + reach < 0 || c.y - reach > extent)
        continue;
      craters.push_back(c);
    }
  }
  std::sort(craters.begin(), craters.end(), [](const Crater& a, const Crater& b) {
    return a.age != b.age ? a.age > b.age : a.order < b.order;  // oldest first
  });
  return craters;
}

void stampCrater(Canvas& canvas, const Crater& c) {
  const double reach = kEjectaRadius * c.radius;
  const auto box = canvas.box(c.x - reach, c.x + reach, c.y - reach, c.y + reach);
  if (box.empty()) return;
  // Pre-impact level: mean of the old surface at the centre and half-way to the rim.
  const double h = c.radius / 2;
  const double level = (canvas.heightNear(c.x, c.y) + canvas.heightNear(c.x + h, c.y) +
                        canvas.heightNear(c.x - h, c.y) + canvas.heightNear(c.x, c.y + h) +
                        canvas.heightNear(c.x, c.y - h)) /
                       5.0;
  const double invR2 = 1.0 / (c.radius * c.radius);
  const double tail = 1.0 / (kEjectaRadius * kEjectaRadius * kEjectaRadius);
  const double reach2 = reach * reach;
  for (int r = box.row0; r <= box.row1; ++r) {
    const double dy = canvas.y(r) - c.y;
    if (dy * dy >= reach2) continue;
    // Only the chord of the ejecta disc on this row.
    const double half = std::sqrt(reach2 - dy * dy);
    const auto chord = canvas.box(c.x - half, c.x + half, c.y, c.y);
    const int col0 = chord.col0, col1 = chord.col1;
    for (int col = col0; col <= col1; ++col) {
      const double dx = canvas.x(col) - c.x;
      const double dist2 = dx * dx + dy * dy;
      if (dist2 >= reach2) continue;
      const double rho2 = dist2 * invR2;
      float& z = canvas.z(r, col);
      if (rho2 <= 1.0) {
        const double bowl = c.rim - c.depth * (1.0 - rho2);
        const double erase = c.freshness * (1.0 - rho2);  // 0 at the rim: no step there
        z = static_cast<float>(z + erase * (level - z) + bowl);
      } else {
        const double inv = 1.0 / (rho2 * std::sqrt(rho2));  // ρ^-3
        z = static_cast<float>(z + c.rim * (inv - tail) / (1.0 - tail));
      }
    }
  }
}

// ----------------------------------------------------------------------------------------------
// Rocks: boulders of 0.2–1.5 m on the surface, cumulative N(>D) ∝ D^-2.5 as in the Surveyor and
// Apollo counts of lunar rocks (Shoemaker & Morris 1970; Cintala & McBride 1995), each a half
// ellipsoid about half as high as wide. A DEM cell holds the mean height over its area, so each
// rock is supersampled 4 × 4 per cell: a 0.2 m rock on a 0.25 m cell is a small bump, not a spike,
// and rocks smaller than a cell are not generated at all. Part of the rocks lie in the ejecta of
// the freshest craters, where blocks concentrate on real surfaces, so rocky patches cluster.

struct RockSpec {
  double density = 0.0;    // rocks per m² with D >= kRockMinDiameter
  double clustered = 0.5;  // fraction placed around fresh craters (when there are any)
};

constexpr double kRockMinDiameter = 0.2;
constexpr double kRockMaxDiameter = 1.5;
constexpr double kRockSlope = 2.5;  // cumulative power-law index
constexpr int kRockSupersample = 4;

void stampRock(Canvas& canvas, double x, double y, double radius, double height) {
  const auto box = canvas.box(x - radius - canvas.cell, x + radius + canvas.cell,
                              y - radius - canvas.cell, y + radius + canvas.cell);
  if (box.empty()) return;
  const double step = canvas.cell / kRockSupersample;
  const double invR2 = 1.0 / (radius * radius);
  for (int r = box.row0; r <= box.row1; ++r) {
    for (int col = box.col0; col <= box.col1; ++col) {
      double sum = 0;
      for (int i = 0; i < kRockSupersample; ++i) {
        const double dy = canvas.y(r) + (i + 0.5) * step - canvas.cell / 2 - y;
        for (int j = 0; j < kRockSupersample; ++j) {
          const double dx = canvas.x(col) + (j + 0.5) * step - canvas.cell / 2 - x;
          const double q = 1.0 - (dx * dx + dy * dy) * invR2;
          if (q > 0) sum += std::sqrt(q);
        }
      }
      if (sum > 0)
        canvas.z(r, col) +=
            static_cast<float>(height * sum / (kRockSupersample * kRockSupersample));
    }
  }
}

void addRocks(Canvas& canvas, const RockSpec& spec, double multiplier,
              const std::vector<Crater>& craters, std::uint64_t seed) {
  const double dLo = std::max(kRockMinDiameter, canvas.cell);
  if (!(spec.density * multiplier > 0) || dLo >= kRockMaxDiameter) return;
  const double extent = canvas.extent();
  auto cumulative = [](double d) { return std::pow(d, -kRockSlope); };
  const double share = (cumulative(dLo) - cumulative(kRockMaxDiameter)) /
                       (cumulative(kRockMinDiameter) - cumulative(kRockMaxDiameter));
  Rng rng(seed);
  const double expected = spec.density * multiplier * share * extent * extent;
  const auto count = static_cast<std::uint64_t>(std::floor(expected + rng.uniform()));

  // Sources of clustered rocks: fresh craters centred on the site, weighted by area.
  std::vector<const Crater*> sources;
  std::vector<double> weights;
  double total = 0;
  for (const auto& c : craters) {
    if (c.freshness < 0.5 || c.radius < 2 * canvas.cell || c.x < 0 || c.y < 0 || c.x > extent ||
        c.y > extent)
      continue;
    total += c.radius * c.radius * c.freshness;
    sources.push_back(&c);
    weights.push_back(total);
  }
  const double lo = cumulative(dLo), hi = cumulative(kRockMaxDiameter);
  for (std::uint64_t i = 0; i < count; ++i) {
    const double diameter = std::pow(lo - rng.uniform() * (lo - hi), -1.0 / kRockSlope);
    const double height = diameter * (0.4 + 0.2 * rng.uniform());
    double x = extent * rng.uniform(), y = extent * rng.uniform();
    const double pick = rng.uniform();
    if (!sources.empty() && rng.uniform() < spec.clustered) {
      const auto at =
          std::upper_bound(weights.begin(), weights.end(), pick * total) - weights.begin();
      const Crater& c = *sources[std::min<std::size_t>(at, sources.size() - 1)];
      // Blocks lie mostly on the upper wall, the rim and the near ejecta.
      const double spread = rng.uniform();  // product of two uniforms: denser near the rim
      const double dist = c.radius * (0.7 + spread * rng.uniform());
      const double theta = 2 * kPi * rng.uniform();
      x = c.x + dist * std::cos(theta);
      y = c.y + dist * std::sin(theta);
    }
    stampRock(canvas, x, y, diameter / 2, height);
  }
}

// ----------------------------------------------------------------------------------------------
// Presets. The numbers were tuned against the class shares above (see the file header).

struct Recipe {
  ReliefSpec relief;
  RidgeSpec ridges;
  CraterSpec craters;
  RockSpec rocks;
};

Recipe moonRecipe() {
  Recipe r;
  // Gentle undulation of the mare plains.
  r.relief = {.slope = 0.035,
              .hurst = 0.8,
              .referenceWavelength = 10.0,
              .maxWavelengthFactor = 1.0,
              .minWavelength = 2.0};
  // Equilibrium cratering, mostly degraded.
  r.craters.density = 0.08;
  r.craters.minCells = 4.0;
  r.craters.minDiameter = 0.0;
  r.craters.maxDiameterFactor = 1.0;
  r.craters.freshnessTime = 0.08;
  r.craters.breakDiameter = 250.0;
  r.craters.largeSlope = 3.2;
  r.rocks = {.density = 0.05, .clustered = 0.6};
  return r;
}

Recipe marsRecipe() {
  Recipe r;
  r.relief = {.slope = 0.05,
              .hurst = 0.75,
              .referenceWavelength = 10.0,
              .maxWavelengthFactor = 1.0,
              .minWavelength = 2.0,
              .roughGain = 8.0,
              .roughOctaves = 2,
              .patchWavelength = 40.0,
              .patchThreshold = 0.15,
              .patchRamp = 0.3};
  r.ridges.enabled = true;
  // A few craters: far below lunar equilibrium, no small ones.
  r.craters.density = 0.01;
  r.craters.minCells = 8.0;
  r.craters.minDiameter = 3.0;
  r.craters.maxDiameterFactor = 0.7;
  r.craters.freshnessTime = 0.3;
  r.craters.complexDepthA = 0.36;
  r.craters.complexDepthB = 0.49;
  r.rocks = {.density = 0.01, .clustered = 0.5};
  return r;
}

void validate(const SyntheticTerrainParams& p) {
  if (p.preset != "moon" && p.preset != "mars")
    throwInvalidParameter("preset", "must be moon or mars, not \"" + p.preset + "\"");
  if (p.size < 16 || p.size > 16384) throwInvalidParameter("size", "must be in [16, 16384] cells");
  if (!(std::isfinite(p.cellSize) && p.cellSize > 0 && p.cellSize <= 1000))
    throwInvalidParameter("cell", "must be a number of metres in (0, 1000]");
  auto multiplier = [](double v, const char* field) {
    if (!(v >= 0 && v <= 10)) throwInvalidParameter(field, "must be a multiplier in [0, 10]");
  };
  multiplier(p.craterDensity, "crater_density");
  multiplier(p.rockDensity, "rock_density");
  multiplier(p.relief, "relief");
}

}  // namespace

terrain::Dem generateTerrain(const SyntheticTerrainParams& params) {
  validate(params);
  const GridGeometry geometry{params.size, params.size, params.cellSize, params.cellSize};
  terrain::Dem dem;
  dem.z = Raster<float>(geometry, 0.0f);
  Canvas canvas{dem.z.values, params.size, params.cellSize};
  const Recipe recipe = params.preset == "moon" ? moonRecipe() : marsRecipe();

  addRelief(canvas, recipe.relief, params.relief, deriveSeed(params.seed, kReliefStream));
  addRidges(canvas, recipe.ridges, params.relief, deriveSeed(params.seed, kRidgeStream));
  const auto craters = sampleCraters(canvas, recipe.craters, params.craterDensity,
                                     deriveSeed(params.seed, kCraterStream));
  for (const auto& c : craters) stampCrater(canvas, c);
  addRocks(canvas, recipe.rocks, params.rockDensity, craters, deriveSeed(params.seed, kRockStream));

  const double extent = params.size * params.cellSize;
  dem.z.geo.valid = true;
  dem.z.geo.geotransform = {0.0, params.cellSize, 0.0, extent, 0.0, -params.cellSize};
  dem.z.geo.crsWkt = bodyCrsWkt(params.preset);
  return dem;
}

std::string bodyCrsWkt(const std::string& body) {
  // IAU mean radii (Archinal et al. 2018): spheres, as the PDS products for these bodies use.
  double radius = 0;
  std::string name;
  if (body == "moon") {
    radius = 1737400.0;
    name = "Moon";
  } else if (body == "mars") {
    radius = 3396190.0;
    name = "Mars";
  } else {
    throwInvalidParameter("body", "must be moon or mars, not \"" + body + "\"");
  }
  OGRSpatialReference srs;
  srs.SetProjCS((name + " Equirectangular").c_str());
  // Inverse flattening 0 = a sphere.
  srs.SetGeogCS(("GCS_" + name).c_str(), ("D_" + name).c_str(), name.c_str(), radius, 0.0,
                "Reference_Meridian", 0.0);
  srs.SetEquirectangular2(0.0, 0.0, 0.0, 0.0, 0.0);
  srs.SetLinearUnits(SRS_UL_METER, 1.0);
  char* wkt = nullptr;
  if (srs.exportToWkt(&wkt) != OGRERR_NONE || wkt == nullptr) {
    CPLFree(wkt);
    throw Error(ErrorCode::InvalidInput, "body", "could not build the CRS of " + name);
  }
  std::string result(wkt);
  CPLFree(wkt);
  return result;
}

}  // namespace rover::maps
