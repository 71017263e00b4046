#include "core/pdm/pdm.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>

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
  if (cs.size() > kMaxComponents)
    throwInvalidParameter("components", "at most " + std::to_string(kMaxComponents) + " components");
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const Gaussian& g = cs[i];
    if (!std::isfinite(g.mean.x())) throwInvalidParameter(field(i, "x"), "must be finite");
    if (!std::isfinite(g.mean.y())) throwInvalidParameter(field(i, "y"), "must be finite");
    if (!(g.sigmaX > 0) || !std::isfinite(g.sigmaX))
      throwInvalidParameter(field(i, "sigma_x"), "must be a positive number of metres");
    if (!(g.sigmaY > 0) || !std::isfinite(g.sigmaY))
      throwInvalidParameter(field(i, "sigma_y"), "must be a positive number of metres");
    if (!std::isfinite(g.rotation)) throwInvalidParameter(field(i, "rotation_deg"), "must be finite");
    if (!(g.weight >= 0) || !std::isfinite(g.weight))
      throwInvalidParameter(field(i, "weight"), "must be a finite number >= 0");
  }
  if (!(totalWeight(cs) > 0)) throwInvalidParameter("components", "the weights sum to 0");
}

void validateGaussians(const std::vector<Gaussian>& cs, const GridGeometry& g) {
  validateGaussians(cs);
  const double w = g.widthMetres(), h = g.heightMetres(), diag = std::hypot(w, h);
  const double sigmaMin = std::min(g.cellWidth, g.cellHeight) / 1000.0, sigmaMax = 100.0 * diag;
  auto text = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const Gaussian& c = cs[i];
    if (c.mean.x() < -diag || c.mean.x() > w + diag)
      throwInvalidParameter(field(i, "x"), "must lie on the map or at most one map diagonal (" + text(diag) +
                                               " m) outside it: [" + text(-diag) + ", " + text(w + diag) + "]");
    if (c.mean.y() < -diag || c.mean.y() > h + diag)
      throwInvalidParameter(field(i, "y"), "must lie on the map or at most one map diagonal (" + text(diag) +
                                               " m) outside it: [" + text(-diag) + ", " + text(h + diag) + "]");
    const std::string range = "must be in [cell/1000, 100 × map diagonal] = [" + text(sigmaMin) + ", " +
                              text(sigmaMax) + "] m";
    if (c.sigmaX < sigmaMin || c.sigmaX > sigmaMax) throwInvalidParameter(field(i, "sigma_x"), range);
    if (c.sigmaY < sigmaMin || c.sigmaY > sigmaMax) throwInvalidParameter(field(i, "sigma_y"), range);
    if (c.weight > 1e9) throwInvalidParameter(field(i, "weight"), "must be in [0, 1e9] (a relative weight)");
  }
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

namespace {

// A cell index from a coordinate in cells, clamped in floating point first (a far-away mean must
// not overflow the int conversion).
int clampedIndex(double v, int lo, int hi) {
  if (!(v > lo)) return lo;  // also NaN
  if (v >= hi) return hi;
  return static_cast<int>(v);
}

// The component's kWindowSigmas-σ ellipse {d : dᵀ Σ⁻¹ d <= k²} around its mean, in the form the
// scan needs: for a horizontal strip of offsets dy ∈ [ya, yb], the range of dx it covers. Built
// from the covariance Σ directly (Σxx, Σxy, Σyy and det Σ = σx²σy²), which stays accurate for
// very elongated components where A·C − B² of the inverse would cancel.
struct Window {
  double sxx, sxy, syy, k;
  double condSd, slope;
  explicit Window(const Gaussian& gs) : k(kWindowSigmas) {
    const double c = std::cos(gs.rotation), s = std::sin(gs.rotation);
    const double vx = gs.sigmaX * gs.sigmaX, vy = gs.sigmaY * gs.sigmaY;
    sxx = c * c * vx + s * s * vy;
    syy = s * s * vx + c * c * vy;
    sxy = c * s * (vx - vy);
    condSd = gs.sigmaX * gs.sigmaY / std::sqrt(syy);  // σ of x given y
    slope = sxy / syy;                                 // E[x | y] = slope · y
  }
  double halfHeight() const { return k * std::sqrt(syy); }
  // dx range of the ellipse over the strip [ya, yb] (already clipped to ±halfHeight()). The left
  // edge x(dy) = slope·dy − halfWidth(dy) is convex, so its minimum is the ellipse's leftmost
  // point when that lies in the strip, else an end of the strip; the right edge likewise.
  std::pair<double, double> xRange(double ya, double yb) const {
    auto half = [&](double dy) { return condSd * std::sqrt(std::max(0.0, k * k - dy * dy / syy)); };
    const double xExtent = k * std::sqrt(sxx), yAtRight = k * sxy / std::sqrt(sxx);
    double lo = std::min(slope * ya - half(ya), slope * yb - half(yb));
    double hi = std::max(slope * ya + half(ya), slope * yb + half(yb));
    if (-yAtRight >= ya && -yAtRight <= yb) lo = -xExtent;
    if (yAtRight >= ya && yAtRight <= yb) hi = xExtent;
    return {lo, hi};
  }
};

// One component's share of the work: its sub-samples per cell side and, row by row, the columns
// of the cells that meet its window (the ±6σ box clipped to the map, then to the 10σ ellipse).
// Shared by the cost check and the discretisation, so the check counts exactly what is done.
struct ComponentScan {
  int s = 1;
  template <typename RowFn>
  static ComponentScan run(const Gaussian& gs, const GridGeometry& g, RowFn&& row) {
    ComponentScan out;
    const Window window(gs);
    const double reach = 6.0 * std::max(gs.sigmaX, gs.sigmaY);
    // Sub-samples per cell side: enough that the narrower σ spans >= ~2 samples.
    const double sMin = std::min(gs.sigmaX, gs.sigmaY);
    out.s = clampedIndex(std::ceil(2.0 * std::max(g.cellWidth, g.cellHeight) / sMin), 1, 16);
    // The ±6σ box (the integration domain), clipped to the map.
    const int c0 = clampedIndex(std::floor((gs.mean.x() - reach) / g.cellWidth), 0, g.cols);
    const int c1 = clampedIndex(std::floor((gs.mean.x() + reach) / g.cellWidth), -1, g.cols - 1);
    // Rows count from the top: y = (rows − row − 0.5)·cellHeight at a centre.
    const int r0 = g.rows - 1 - clampedIndex(std::floor((gs.mean.y() + reach) / g.cellHeight), -1, g.rows - 1);
    const int r1 = g.rows - 1 - clampedIndex(std::floor((gs.mean.y() - reach) / g.cellHeight), 0, g.rows);
    const double yHalf = window.halfHeight();
    for (int r = r0; r <= r1; ++r) {
      // This row's strip of y offsets from the mean, clipped to the ellipse.
      const double ya = std::max((g.rows - r - 1) * g.cellHeight - gs.mean.y(), -yHalf);
      const double yb = std::min((g.rows - r) * g.cellHeight - gs.mean.y(), yHalf);
      if (ya > yb) continue;
      const auto [xlo, xhi] = window.xRange(ya, yb);
      const int ca = std::max(c0, clampedIndex(std::floor((gs.mean.x() + xlo) / g.cellWidth), 0, g.cols));
      const int cb = std::min(c1, clampedIndex(std::floor((gs.mean.x() + xhi) / g.cellWidth), -1, g.cols - 1));
      if (ca <= cb) row(r, ca, cb, out.s);
    }
    return out;
  }
};

}  // namespace

double discretisationCost(const std::vector<Gaussian>& cs, const GridGeometry& g) {
  double samples = 0;
  for (const auto& gs : cs) {
    if (gs.weight == 0) continue;
    ComponentScan::run(gs, g, [&](int, int ca, int cb, int s) { samples += double(cb - ca + 1) * s * s; });
  }
  return samples;
}

namespace {

// discretise once the components are known to be in range for the map they belong to.
Raster<float> discretiseChecked(const std::vector<Gaussian>& cs, const GridGeometry& g,
                                const std::vector<std::uint8_t>& valid) {
  if (const double cost = discretisationCost(cs, g); cost > kMaxDiscretisationSamples) {
    std::ostringstream m;
    m << "would take " << cost << " density evaluations on this map, more than the " << kMaxDiscretisationSamples
      << " a PDM may cost: use fewer, narrower or better placed components (or a PDM raster)";
    throwInvalidParameter("components", m.str());
  }
  std::vector<double> mass(g.cellCount(), 0.0);
  const double wTotal = totalWeight(cs);
  const double area = g.cellWidth * g.cellHeight;
  for (const auto& gs : cs) {
    if (gs.weight == 0) continue;
    Quadratic q = quadratic(gs);
    ComponentScan::run(gs, g, [&](int r, int ca, int cb, int s) {
      const double wNorm = gs.weight / wTotal * q.norm * area / (s * s);
      for (int c = ca; c <= cb; ++c) {
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
    });
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

}  // namespace

Raster<float> discretise(const std::vector<Gaussian>& cs, const GridGeometry& g,
                         const std::vector<std::uint8_t>& valid) {
  validateGaussians(cs, g);
  return discretiseChecked(cs, g, valid);
}

Raster<float> discretiseOnWindow(const std::vector<Gaussian>& cs, const GridGeometry& map,
                                 const GridGeometry& window, const Eigen::Vector2d& origin,
                                 const std::vector<std::uint8_t>& valid) {
  // In range for the map they were made on; the window's own bounds (one window diagonal) would
  // refuse a wide component centred a kilometre off a 150 m area, whose mass there is real.
  validateGaussians(cs, map);
  std::vector<Gaussian> moved;
  const Eigen::Vector2d size(window.widthMetres(), window.heightMetres());
  for (Gaussian c : cs) {
    c.mean -= origin;
    // A component whose kWindowSigmas ellipse cannot reach the window adds nothing there (the scan
    // would visit no cell): left out, so its distance costs no work.
    const Eigen::Vector2d gap = (c.mean.cwiseMax(Eigen::Vector2d::Zero()).cwiseMin(size) - c.mean).cwiseAbs();
    if (gap.norm() > kWindowSigmas * std::max(c.sigmaX, c.sigmaY)) continue;
    moved.push_back(c);
  }
  if (moved.empty())
    throw Error(ErrorCode::InvalidInput, "components", "no probability mass falls on valid cells of the area");
  return discretiseChecked(moved, window, valid);
}

std::vector<Gaussian> randomGaussians(const GridGeometry& g, int count, std::uint64_t seed) {
  if (count < 1 || count > static_cast<int>(kMaxComponents))
    throwInvalidParameter("count", "must be in [1, " + std::to_string(kMaxComponents) + "]");
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
