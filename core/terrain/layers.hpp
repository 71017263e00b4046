#pragma once
// Terrain layers from a DEM (SPEC §2), pure functions on Dem values.
//
// Display layers use Horn's (1981) 3×3 gradient with exactly gdaldem's definitions, so the two agree
// number for number: border cells and cells whose window holds nodata are NaN (gdaldem without
// -compute_edges). The traversability layer is paper 001 §3.4's worst-case 8-neighbour slope.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>

#include "core/terrain/dem.hpp"

namespace rover::terrain {

// Horn's 3×3 sums at the interior cells of row r (1 ≤ r ≤ rows − 2), named as in Horn (1981) and
// gdaldem with the window
//   a b c
//   d e f
//   g h i
// sx = (a + 2d + g) − (c + 2f + i) and sy = (g + 2h + i) − (a + 2b + c), kept and summed in float as
// gdaldem does (its window type is the band's float: on near-flat cells the aspect is sensitive to
// that rounding, and we want gdaldem's numbers). fn(c, sx, sy) for each column 1 ≤ c ≤ cols − 2
// whose window has no NaN. The gradient of slopeHorn, aspectHorn and hillshade is then
// x = sx / (8·dem.dx(r)), which is −∂z/∂x, and y = sy / (8·nsres) with nsres = −dem.dy(), +∂z/∂y.
// Shared, so a renderer that draws straight from the sums (maps/render.cpp) has the layers' numbers.
template <class Fn>
void hornRow(const Dem& dem, int r, Fn&& fn) {
  const int cols = dem.z.geometry.cols;
  const float* up = &dem.z(r - 1, 0);
  const float* row = &dem.z(r, 0);
  const float* down = &dem.z(r + 1, 0);
  for (int c = 1; c < cols - 1; ++c) {
    const float a = up[c - 1], b = up[c], cc = up[c + 1], d = row[c - 1], f = row[c + 1], g = down[c - 1],
                h = down[c], i = down[c + 1];
    if (std::isnan(double(a) + b + cc + d + f + g + h + i + row[c])) continue;
    fn(c, (a + d + d + g) - (cc + f + f + i), (g + h + h + i) - (a + b + b + cc));
  }
}

// Slope in degrees of Horn's gradient (x, y) as slopeHorn computes it, before its rounding to float.
inline double slopeDegrees(double x, double y) { return std::atan(std::sqrt(x * x + y * y)) * (180.0 / std::numbers::pi); }

// Horn slope in degrees (gdaldem slope).
Raster<float> slopeHorn(const Dem& dem);
// Aspect in degrees clockwise from north, the direction the slope faces (gdaldem aspect); NaN on
// flat cells as well.
Raster<float> aspectHorn(const Dem& dem);
// Shaded relief 1..255 (gdaldem hillshade; azimuth clockwise from north, altitude above horizon).
Raster<float> hillshade(const Dem& dem, double azimuthDeg = 315.0, double altitudeDeg = 45.0,
                        double zFactor = 1.0);

// KeepOut is for planning only (core/planning/keep_out.hpp): a map cell an operator's keep-out
// zone overlaps. No terrain layer holds it; every check that blocks Impassable blocks it too.
enum class TerrainClass : std::uint8_t {
  Traversable = 0,
  HighRisk = 1,
  Impassable = 2,
  NoData = 3,
  KeepOut = 4,
};
const char* terrainClassName(TerrainClass c);

struct TraversabilityParams {
  double highRiskDeg = 10.0;    // paper 001 §3.4: 10° <= θ < 15° is high risk
  double impassableDeg = 15.0;  // θ >= 15° impassable (paper 004's "10°" is a typo, SPEC §2)
};

struct ClassShares {
  std::array<std::int64_t, 4> counts{};  // indexed by TerrainClass
  double percent(TerrainClass c) const;  // of all cells, nodata included
};

struct Traversability {
  Raster<std::uint8_t> classes;  // TerrainClass per cell
  Raster<float> worstSlopeDeg;   // empty unless asked for (saves 4 bytes a cell on big rasters)
  ClassShares shares;
};

// For every cell the slope to each of its 8 neighbours, θ = atan(|Δh| / d) with d the horizontal
// distance (dx, dy or the diagonal); the cell takes the worst. Neighbours outside the grid or
// without data are skipped; a cell without data is NoData. `threads` = 0 uses all cores.
Traversability traversability(const Dem& dem, const TraversabilityParams& params = {},
                              bool keepSlope = false, unsigned threads = 0);

// Height and gradient at a local point by bilinear interpolation between cell centres
// (SPEC §2 roll/pitch); nullopt outside the grid or next to nodata.
struct SurfacePoint {
  double height = 0;
  double dzdx = 0;  // east
  double dzdy = 0;  // north
};
std::optional<SurfacePoint> surfaceAt(const Dem& dem, double x, double y);

// surfaceAt's arithmetic, inline, with the height left out when `Height` is false: the RRT* edge
// loops call it millions of times per mission and need only the gradient (a call and the unused
// height were a fifth of a team mission's profile, issue 10). False where surfaceAt is nullopt;
// the numbers are surfaceAt's, operation for operation.
template <bool Height>
inline bool bilinearSurfaceAt(const Dem& dem, double x, double y, SurfacePoint& s) {
  const GridGeometry& g = dem.geometry();
  if (g.rows < 2 || g.cols < 2 || !std::isfinite(x) || !std::isfinite(y)) return false;
  if (x < 0 || y < 0 || x > g.widthMetres() || y > g.heightMetres()) return false;
  // Pixel coordinates of the point relative to cell centres; clamped so points within half a cell
  // of the border use the outermost square of centres.
  const double u = std::clamp(x / g.cellWidth - 0.5, 0.0, g.cols - 1.0);
  const double v = std::clamp((g.rows - y / g.cellHeight) - 0.5, 0.0, g.rows - 1.0);
  const int c0 = std::min(static_cast<int>(u), g.cols - 2), r0 = std::min(static_cast<int>(v), g.rows - 2);
  const double fu = u - c0, fv = v - r0;
  const double z00 = dem.z(r0, c0), z01 = dem.z(r0, c0 + 1), z10 = dem.z(r0 + 1, c0),
               z11 = dem.z(r0 + 1, c0 + 1);
  if (std::isnan(z00 + z01 + z10 + z11)) return false;
  if constexpr (Height) s.height = (1 - fv) * ((1 - fu) * z00 + fu * z01) + fv * ((1 - fu) * z10 + fu * z11);
  const double dzdu = (1 - fv) * (z01 - z00) + fv * (z11 - z10);
  const double dzdv = (1 - fu) * (z10 - z00) + fu * (z11 - z01);
  // The row's cell width only matters on maps with per-row widths (geographic grids); the
  // rounding is skipped on the rest (it showed up in the RRT* profile, issue 10).
  s.dzdx = dzdu / (dem.rowCellWidth.empty()
                       ? g.cellWidth
                       : dem.dx(std::clamp(static_cast<int>(std::lround(v)), 0, g.rows - 1)));
  s.dzdy = -dzdv / dem.dy();  // v grows southwards
  return true;
}

// Roll and pitch (radians) of a rover at (x, y) with heading ψ (radians counter-clockwise from
// east): pitch = atan(∇h·(cosψ, sinψ)), roll = atan(∇h·(−sinψ, cosψ)); positive pitch = nose up.
struct Attitude {
  double roll = 0;
  double pitch = 0;
};
std::optional<Attitude> attitudeAt(const Dem& dem, double x, double y, double heading);

}  // namespace rover::terrain
