#include "core/pdm/pdm.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/error.hpp"
#include "core/common/random.hpp"

namespace rover::pdm {

namespace {

std::string field(std::size_t i, const char* name) {
  return "components[" + std::to_string(i) + "]." + name;
}

// Inverse covariance terms of a rotated Gaussian: q(d) = A dx² + 2B dx dy + C dy².
struct Quadratic {
  double A, B, C, norm;
};

Quadratic quadratic(const Gaussian& gs) {
  const double c = std::cos(gs.rotation), s = std::sin(gs.rotation);
  const double ix = 1.0 / (gs.sigmaX * gs.sigmaX), iy = 1.0 / (gs.sigmaY * gs.sigmaY);
  return {c * c * ix + s * s * iy, c * s * (ix - iy), s * s * ix + c * c * iy,
          1.0 / (2.0 * std::numbers::pi * gs.sigmaX * gs.sigmaY)};
}

double totalWeight(const std::vector<Gaussian>& cs) {
  double w = 0;
  for (const auto& c : cs) w += c.weight;
  return w;
}

}  // namespace

void validateGaussians(const std::vector<Gaussian>& cs) {
  if (cs.empty()) throwInvalidParameter("components", "at least one Gaussian component is needed");
  if (cs.size() > 1000) throwInvalidParameter("components", "at most 1000 components");
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const Gaussian& g = cs[i];
    if (!g.mean.allFinite()) throwInvalidParameter(field(i, "mean"), "must be finite");
    if (!(g.sigmaX > 0) || !std::isfinite(g.sigmaX))
      throwInvalidParameter(field(i, "sigma_x"), "must be a positive number of metres");
    if (!(g.sigmaY > 0) || !std::isfinite(g.sigmaY))
      throwInvalidParameter(field(i, "sigma_y"), "must be a positive number of metres");
    if (!std::isfinite(g.rotation)) throwInvalidParameter(field(i, "rotation"), "must be finite");
    if (!(g.weight >= 0) || !std::isfinite(g.weight))
      throwInvalidParameter(field(i, "weight"), "must be a finite number >= 0");
  }
  if (!(totalWeight(cs) > 0)) throwInvalidParameter("components", "the weights sum to 0");
}

double density(const std::vector<Gaussian>& cs, const Eigen::Vector2d& xy) {
  double sum = 0;
  for (const auto& gs : cs) {
    Quadratic q = quadratic(gs);
    Eigen::Vector2d d = xy - gs.mean;
    sum += gs.weight * q.norm *
           std::exp(-0.5 * (q.A * d.x() * d.x() + 2 * q.B * d.x() * d.y() + q.C * d.y() * d.y()));
  }
  return sum / totalWeight(cs);
}

Raster<float> discretise(const std::vector<Gaussian>& cs, const GridGeometry& g,
                         const std::vector<std::uint8_t>& valid) {
  validateGaussians(cs);
  std::vector<double> mass(g.cellCount(), 0.0);
  const double wTotal = totalWeight(cs);
  const double area = g.cellWidth * g.cellHeight;
  for (const auto& gs : cs) {
    if (gs.weight == 0) continue;
    Quadratic q = quadratic(gs);
    const double reach = 6.0 * std::max(gs.sigmaX, gs.sigmaY);
    // Sub-samples per cell side: enough that the narrower σ spans >= ~2 samples.
    const double sMin = std::min(gs.sigmaX, gs.sigmaY);
    const int s = std::clamp(static_cast<int>(std::ceil(2.0 * std::max(g.cellWidth, g.cellHeight) / sMin)), 1, 16);
    const int c0 = std::max(0, static_cast<int>(std::floor((gs.mean.x() - reach) / g.cellWidth)));
    const int c1 = std::min(g.cols - 1, static_cast<int>(std::floor((gs.mean.x() + reach) / g.cellWidth)));
    // Rows count from the top: y = (rows − row − 0.5)·cellHeight at a centre.
    const int r0 = std::max(0, g.rows - 1 - static_cast<int>(std::floor((gs.mean.y() + reach) / g.cellHeight)));
    const int r1 = std::min(g.rows - 1, g.rows - 1 - static_cast<int>(std::floor((gs.mean.y() - reach) / g.cellHeight)));
    const double wNorm = gs.weight / wTotal * q.norm * area / (s * s);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        double sum = 0;
        for (int a = 0; a < s; ++a) {
          const double y = (g.rows - r - (a + 0.5) / s) * g.cellHeight - gs.mean.y();
          for (int b = 0; b < s; ++b) {
            const double x = (c + (b + 0.5) / s) * g.cellWidth - gs.mean.x();
            sum += std::exp(-0.5 * (q.A * x * x + 2 * q.B * x * y + q.C * y * y));
          }
        }
        mass[g.index(r, c)] += wNorm * sum;
      }
    }
  }
  double total = 0;
  for (int i = 0; i < g.cellCount(); ++i) {
    if (!valid.empty() && !valid[i]) mass[i] = 0;
    total += mass[i];
  }
  if (!(total > 0))
    throw Error(ErrorCode::InvalidInput, "components",
                "no probability mass falls on valid cells of the map");
  Raster<float> out(g, 0.0f);
  for (int i = 0; i < g.cellCount(); ++i) out.at(i) = static_cast<float>(mass[i] / total);
  return out;
}

std::vector<Gaussian> randomGaussians(const GridGeometry& g, int count, std::uint64_t seed) {
  if (count < 1 || count > 1000) throwInvalidParameter("count", "must be in [1, 1000]");
  Rng rng(deriveSeed(seed, 3));
  const double side = std::min(g.widthMetres(), g.heightMetres());
  std::vector<Gaussian> out;
  for (int i = 0; i < count; ++i) {
    Gaussian gs;
    gs.mean = {rng.uniform() * g.widthMetres(), rng.uniform() * g.heightMetres()};
    gs.sigmaX = side * (0.05 + 0.15 * rng.uniform());
    gs.sigmaY = side * (0.05 + 0.15 * rng.uniform());
    gs.rotation = rng.uniform() * std::numbers::pi;
    out.push_back(gs);
  }
  return out;
}

Raster<float> normaliseWeights(const Raster<float>& weights, const std::vector<std::uint8_t>& valid) {
  const int n = weights.geometry.cellCount();
  double total = 0;
  for (int i = 0; i < n; ++i) {
    float v = weights.at(i);
    if (std::isnan(v) || (!valid.empty() && !valid[i])) continue;
    if (std::isinf(v) || v < 0)
      throw Error(ErrorCode::InvalidInput, "pdm", "PDM raster values must be finite and >= 0");
    total += v;
  }
  if (!(total > 0)) throw Error(ErrorCode::InvalidInput, "pdm", "the PDM raster sums to 0 on the map");
  Raster<float> out(weights.geometry, 0.0f);
  out.geo = weights.geo;
  for (int i = 0; i < n; ++i) {
    float v = weights.at(i);
    if (std::isnan(v) || (!valid.empty() && !valid[i])) continue;
    out.at(i) = static_cast<float>(v / total);
  }
  return out;
}

}  // namespace rover::pdm
