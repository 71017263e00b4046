#include "core/terrain/layers.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/error.hpp"
#include "core/common/parallel.hpp"
#include "core/terrain/hillshade_light.hpp"

namespace rover::terrain {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// fn(x, y) of Horn's gradient (hornRow) at every interior cell whose window holds no nodata.
template <class Fn>
Raster<float> mapInterior(const Dem& dem, Fn&& fn) {
  const GridGeometry& g = dem.geometry();
  Raster<float> out(g, kNaN);
  out.geo = dem.z.geo;
  // A tile (256² plus its halo) is rendered on the server's work pool, one tile a thread: starting
  // threads for it cost more than its rows (a third of a cold tile's time went to thread starts).
  // Whole-map layers take every core. Rows are independent, so the result is the same either way.
  constexpr int kSerialCells = 1 << 20;
  const unsigned threads = g.cellCount() < kSerialCells ? 1 : 0;
  parallelFor(std::max(0, g.rows - 2), threads, [&](std::size_t k) {
    const int r = static_cast<int>(k) + 1;
    const double ewres = dem.dx(r), nsres = -dem.dy();
    float* o = &out(r, 0);
    hornRow(dem, r, [&](int c, float sx, float sy) {
      double x = sx / (8.0 * ewres);
      double y = sy / (8.0 * nsres);
      o[c] = static_cast<float>(fn(x, y));
    });
  });
  return out;
}

}  // namespace

Raster<float> slopeHorn(const Dem& dem) {
  // sqrt(x² + y²) as gdaldem computes it; hypot's overflow guard costs a tenth of a slope tile and
  // Horn's gradients of a DEM are nowhere near overflow.
  return mapInterior(dem, [](double x, double y) { return slopeDegrees(x, y); });
}

Raster<float> aspectHorn(const Dem& dem) {
  return mapInterior(dem, [](double x, double y) -> double {
    // Here x = −∂z/∂x and y = ∂z/∂y (north). gdaldem takes atan2 of its unscaled Horn sums,
    // atan2(dy_rows, −dx) = atan2(−y, x) up to a positive factor per axis, then turns it into
    // an azimuth clockwise from north. Using the scaled gradient keeps non-square pixels right
    // and changes nothing for square ones.
    if (x == 0 && y == 0) return std::numeric_limits<double>::quiet_NaN();  // flat
    double aspect = std::atan2(-y, x) * kRadToDeg;
    aspect = aspect > 90.0 ? 450.0 - aspect : 90.0 - aspect;
    return aspect == 360.0 ? 0.0 : aspect;
  });
}

Raster<float> hillshade(const Dem& dem, double azimuthDeg, double altitudeDeg, double zFactor) {
  return mapInterior(dem, HillshadeLight(azimuthDeg, altitudeDeg, zFactor));
}

const char* terrainClassName(TerrainClass c) {
  switch (c) {
    case TerrainClass::Traversable: return "traversable";
    case TerrainClass::HighRisk: return "high_risk";
    case TerrainClass::Impassable: return "impassable";
    case TerrainClass::NoData: return "nodata";
    case TerrainClass::KeepOut: return "keep_out";
  }
  return "?";
}

double ClassShares::percent(TerrainClass c) const {
  std::int64_t total = counts[0] + counts[1] + counts[2] + counts[3];
  return total == 0 ? 0.0 : 100.0 * counts[static_cast<int>(c)] / static_cast<double>(total);
}

Traversability traversability(const Dem& dem, const TraversabilityParams& p, bool keepSlope,
                              unsigned threads) {
  if (!(p.highRiskDeg > 0 && p.highRiskDeg < p.impassableDeg && p.impassableDeg < 90))
    throwInvalidParameter("impassable_deg", "thresholds must satisfy 0 < high risk < impassable < 90");
  const GridGeometry& g = dem.geometry();
  Traversability t;
  t.classes = Raster<std::uint8_t>(g, 0);
  t.classes.geo = dem.z.geo;
  if (keepSlope) {
    t.worstSlopeDeg = Raster<float>(g, kNaN);
    t.worstSlopeDeg.geo = dem.z.geo;
  }
  // Compare |Δh|/d against tan(threshold) instead of taking 8 arctangents per cell.
  const double tanHigh = std::tan(p.highRiskDeg / kRadToDeg);
  const double tanImp = std::tan(p.impassableDeg / kRadToDeg);
  const unsigned nThreads = threads == 0 ? hardwareThreads() : threads;
  std::vector<std::array<std::int64_t, 4>> partial(g.rows);
  parallelFor(g.rows, nThreads, [&](std::size_t k) {
    const int r = static_cast<int>(k);
    const double dx = dem.dx(r), dy = dem.dy();
    const float invDx = static_cast<float>(1.0 / dx), invDy = static_cast<float>(1.0 / dy);
    const float invDiag = static_cast<float>(1.0 / std::hypot(dx, dy));
    const float inv[8] = {invDx, invDiag, invDy, invDiag, invDx, invDiag, invDy, invDiag};
    static constexpr int dr[8] = {0, -1, -1, -1, 0, 1, 1, 1};
    static constexpr int dc[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    const float* row = &dem.z(r, 0);
    const float* up = r > 0 ? &dem.z(r - 1, 0) : nullptr;
    const float* down = r + 1 < g.rows ? &dem.z(r + 1, 0) : nullptr;
    std::array<std::int64_t, 4> counts{};
    std::uint8_t* cls = &t.classes(r, 0);
    for (int c = 0; c < g.cols; ++c) {
      const float h = row[c];
      if (std::isnan(h)) {
        cls[c] = static_cast<std::uint8_t>(TerrainClass::NoData);
        ++counts[3];
        continue;
      }
      float worst = 0.0f;  // NaN neighbours fail every comparison, so nodata is skipped
      if (up && down && c > 0 && c + 1 < g.cols) {
        const float s[8] = {row[c + 1], up[c + 1], up[c],   up[c - 1],
                            row[c - 1], down[c - 1], down[c], down[c + 1]};
        for (int n = 0; n < 8; ++n) {
          float v = std::fabs(s[n] - h) * inv[n];
          if (v > worst) worst = v;
        }
      } else {
        for (int n = 0; n < 8; ++n) {
          int rr = r + dr[n], cc = c + dc[n];
          if (!g.contains(rr, cc)) continue;
          float v = std::fabs(dem.z(rr, cc) - h) * inv[n];
          if (v > worst) worst = v;
        }
      }
      TerrainClass k2 = worst >= tanImp    ? TerrainClass::Impassable
                        : worst >= tanHigh ? TerrainClass::HighRisk
                                           : TerrainClass::Traversable;
      cls[c] = static_cast<std::uint8_t>(k2);
      ++counts[static_cast<int>(k2)];
      if (keepSlope) t.worstSlopeDeg(r, c) = static_cast<float>(std::atan(worst) * kRadToDeg);
    }
    partial[r] = counts;
  });
  for (const auto& c : partial)
    for (int k = 0; k < 4; ++k) t.shares.counts[k] += c[k];
  return t;
}

std::optional<SurfacePoint> surfaceAt(const Dem& dem, double x, double y) {
  SurfacePoint s;
  if (!bilinearSurfaceAt<true>(dem, x, y, s)) return std::nullopt;
  return s;
}

std::optional<Attitude> attitudeAt(const Dem& dem, double x, double y, double heading) {
  auto s = surfaceAt(dem, x, y);
  if (!s) return std::nullopt;
  const double c = std::cos(heading), si = std::sin(heading);
  return Attitude{std::atan(-s->dzdx * si + s->dzdy * c), std::atan(s->dzdx * c + s->dzdy * si)};
}

}  // namespace rover::terrain
