#include "maps/terrain_relief.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/common/random.hpp"

namespace rover::maps::synthetic {

namespace {

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

constexpr double kMinNoiseCells = 8.0;  // shorter octaves would be aliased by the grid
constexpr double kLacunarity = 1.93;    // not 2, so octave lattices never line up

double smoothstep01(double t) {
  if (t <= 0) return 0.0;
  if (t >= 1) return 1.0;
  return t * t * (3 - 2 * t);
}

constexpr double kMinRidgeCells = 12.0;

}  // namespace

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

}  // namespace rover::maps::synthetic
