#include "core/coverage/terrain_world.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/common/error.hpp"

namespace rover::coverage {

namespace {

// A slack for extents that are whole multiples of the cell up to rounding (600 × 0.2499999998).
constexpr double kSlack = 1e-6;

// The smallest number >= v with 3 significant digits.
double roundUp3(double v) {
  const double q = std::pow(10.0, std::floor(std::log10(v)) - 2);
  return std::ceil(v / q - 1e-6) * q;
}

std::int64_t cellsOf(const GridGeometry& g) {
  return static_cast<std::int64_t>(g.rows) * g.cols;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, std::fabs(v) >= 1000 ? "%.0f" : "%.4g", v);
  return buf;
}

}  // namespace

GridGeometry coverageGrid(const GridGeometry& map, double cell) {
  auto along = [cell](double extent) {
    return static_cast<int>(std::min(2e9, std::floor(extent / cell + kSlack)));
  };
  return {along(map.heightMetres()), along(map.widthMetres()), cell, cell};
}

double nativeCoverageCell(const GridGeometry& map) {
  return std::max(map.cellWidth, map.cellHeight);
}

double defaultCoverageCell(const GridGeometry& map, std::int64_t cellBudget) {
  double cell = nativeCoverageCell(map);
  const double area = map.widthMetres() * map.heightMetres();
  if (cellBudget > 0 && area / (cell * cell) > static_cast<double>(cellBudget))
    cell = roundUp3(std::sqrt(area / static_cast<double>(cellBudget)));
  // Whole cells only: the floor can leave the count just over; step up a digit at a time.
  for (int i = 0; i < 1000 && cellBudget > 0 && cellsOf(coverageGrid(map, cell)) > cellBudget; ++i)
    cell = roundUp3(cell * 1.001);
  return cell;
}

double resolveCoverageCell(const GridGeometry& map, double cell, std::int64_t cellBudget) {
  if (!(cell > 0)) cell = defaultCoverageCell(map, cellBudget);
  const GridGeometry g = coverageGrid(map, cell);
  if (g.rows < 2 || g.cols < 2)
    throwInvalidParameter("coverage_cell", "a coverage cell of " + num(cell) +
                                               " m leaves fewer than 2 × 2 cells on this map (" +
                                               num(map.widthMetres()) + " × " +
                                               num(map.heightMetres()) + " m)");
  if (cellsOf(g) > kMaxCoverageCells)
    throwInvalidParameter("coverage_cell",
                          "a coverage cell of " + num(cell) + " m gives " + std::to_string(g.rows) +
                              " × " + std::to_string(g.cols) + " cells, more than the " +
                              std::to_string(kMaxCoverageCells) + " a coverage grid may hold; " +
                              num(defaultCoverageCell(map, kMaxCoverageCells)) + " m fits");
  return cell;
}

World worldFromDem(const terrain::Dem& dem, double cell,
                   const terrain::TraversabilityParams& params) {
  const GridGeometry& m = dem.geometry();
  const GridGeometry g = coverageGrid(m, cell);
  if (g.rows < 1 || g.cols < 1) return World{Raster<std::uint8_t>(g, 0), Raster<double>(g, 0.0)};
  const terrain::Traversability t = terrain::traversability(dem, params);
  auto blocked = [&](int i) {
    auto c = static_cast<terrain::TerrainClass>(t.classes.at(i));
    return c == terrain::TerrainClass::Impassable || c == terrain::TerrainClass::NoData;
  };
  World w;
  w.obstacles = Raster<std::uint8_t>(g, 0);
  w.heights = Raster<double>(g, 0.0);
  std::vector<int> count(static_cast<std::size_t>(g.cellCount()), 0);
  // Every pixel into the coverage cell holding its centre.
  for (int r = 0; r < m.rows; ++r) {
    const double y = (m.rows - r - 0.5) * m.cellHeight;
    const int fromBottom = static_cast<int>(std::floor(y / cell));
    if (fromBottom >= g.rows) continue;  // the strip left out along the north edge
    const int gr = g.rows - 1 - fromBottom;
    for (int c = 0; c < m.cols; ++c) {
      const int gc = static_cast<int>(std::floor((c + 0.5) * m.cellWidth / cell));
      if (gc >= g.cols) break;  // ... and along the east edge
      const int i = g.index(gr, gc), p = m.index(r, c);
      if (blocked(p)) {
        w.obstacles.at(i) = 1;
        continue;
      }
      w.heights.at(i) += dem.z.at(p);
      ++count[i];
    }
  }
  // Means, and the cells finer than a pixel (no centre of their own): the pixel under theirs.
  for (int i = 0; i < g.cellCount(); ++i) {
    if (w.obstacles.at(i)) {
      w.heights.at(i) = 0.0;  // never read: obstacles are never entered
      continue;
    }
    if (count[i] > 0) {
      w.heights.at(i) /= count[i];
      continue;
    }
    const Eigen::Vector2d centre = cellToLocal(g, g.cell(i));
    const auto under = localToCell(m, centre);
    if (!under || blocked(m.index(*under))) {
      w.obstacles.at(i) = 1;
      continue;
    }
    const auto s = terrain::surfaceAt(dem, centre.x(), centre.y());
    w.heights.at(i) = s ? s->height : dem.z.at(m.index(*under));
  }
  // Means of pixels can differ by more than the pixels do (a diagonal move, two pixels in one
  // cell): the coverage grid's own worst slope also makes an obstacle, so no move between free
  // cells ever pitches at the impassable slope or more. One pass is enough: a slope between two
  // cells that both stay free was below the threshold for each of them.
  terrain::Dem coarse;
  coarse.z = Raster<float>(g, 0.0f);
  for (int i = 0; i < g.cellCount(); ++i)
    coarse.z.at(i) = w.obstacles.at(i) ? NAN : static_cast<float>(w.heights.at(i));
  const terrain::Traversability ct = terrain::traversability(coarse, params);
  for (int i = 0; i < g.cellCount(); ++i)
    if (ct.classes.at(i) == static_cast<std::uint8_t>(terrain::TerrainClass::Impassable)) {
      w.obstacles.at(i) = 1;
      w.heights.at(i) = 0.0;
    }
  // The grid's own geotransform, so an export of the world lands where the map is: the local
  // frame maps linearly to the DEM's pixels (maps/georef.hpp), and the grid's top edge lies at
  // g.rows·cell metres north of the map's south edge.
  if (dem.z.geo.valid) {
    const auto& gt = dem.z.geo.geotransform;
    const double col0 = 0.0, row0 = m.rows - g.rows * cell / m.cellHeight;
    const double sx = cell / m.cellWidth, sy = cell / m.cellHeight;
    GeoReference geo = dem.z.geo;
    geo.geotransform = {gt[0] + col0 * gt[1] + row0 * gt[2], gt[1] * sx, gt[2] * sy,
                        gt[3] + col0 * gt[4] + row0 * gt[5], gt[4] * sx, gt[5] * sy};
    w.obstacles.geo = geo;
    w.heights.geo = geo;
  }
  return w;
}

World worldFromDem(const terrain::Dem& dem, const terrain::TraversabilityParams& params) {
  const GridGeometry& m = dem.geometry();
  if (!(m.cellWidth > 0) || std::fabs(m.cellWidth - m.cellHeight) > 1e-9 * m.cellWidth ||
      !dem.rowCellWidth.empty())
    throw Error(ErrorCode::InvalidInput, "coverage_cell",
                "the DEM's cells are not square: give a coverage cell size");
  return worldFromDem(dem, m.cellWidth, params);
}

}  // namespace rover::coverage
