#include "maps/terrain_craters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/common/random.hpp"

namespace rover::maps::synthetic {

namespace {

constexpr double kFreshDepthRatio = 0.196;     // Pike 1977
constexpr double kRimToDepth = 0.036 / 0.196;  // Pike 1977, h_r / d
constexpr double kDegradedDepthRatio = 0.035;  // a heavily degraded, shallow crater
constexpr double kEjectaRadius = 2.5;          // in crater radii, where the ejecta taper ends

double freshCraterDepth(const CraterSpec& spec, double diameter) {
  const double simple = kFreshDepthRatio * diameter;
  const double complex =
      1000.0 * spec.complexDepthA * std::pow(diameter / 1000.0, spec.complexDepthB);
  return std::min(simple, complex);
}

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

}  // namespace

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

}  // namespace rover::maps::synthetic
