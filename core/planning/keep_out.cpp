#include "core/planning/keep_out.hpp"

#include "core/terrain/layers.hpp"

namespace rover {

int KeepOut::zoneAt(const Eigen::Vector2d& p) const {
  for (std::size_t z = 0; z < zones.size(); ++z)
    if (insidePolygon(zones[z], p)) return static_cast<int>(z);
  return -1;
}

int KeepOut::zoneOverlapping(const GridGeometry& g, CellIndex c, double grow) const {
  // The one cell as a 1 × 1 grid: the zones moved so that the cell's lower-left corner is the
  // origin, through the same rasterisation as every other check.
  const Eigen::Vector2d corner = cellToLocal(g, c) - Eigen::Vector2d(g.cellWidth, g.cellHeight) / 2;
  const GridGeometry one{1, 1, g.cellWidth, g.cellHeight};
  for (std::size_t z = 0; z < zones.size(); ++z) {
    Polygon moved = zones[z];
    for (Ring& ring : moved)
      for (auto& v : ring) v -= corner;
    if (polygonCells(one, {moved}, grow)[0]) return static_cast<int>(z);
  }
  return -1;
}

std::int64_t applyKeepOut(Raster<std::uint8_t>& classes, const KeepOut& keepOut, double margin) {
  if (keepOut.empty()) return 0;
  const auto impassable = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  const auto zoned = static_cast<std::uint8_t>(terrain::TerrainClass::KeepOut);
  const std::vector<std::uint8_t> hard = keepOut.cells(classes.geometry);
  const std::vector<std::uint8_t> soft =
      margin > 0 ? keepOut.cells(classes.geometry, margin) : std::vector<std::uint8_t>{};
  std::int64_t newlyBlocked = 0;
  for (int i = 0; i < classes.geometry.cellCount(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const bool inZone = hard[k] != 0, nearZone = !soft.empty() && soft[k] != 0;
    if (!inZone && !nearZone) continue;
    if (classes.at(i) < impassable) ++newlyBlocked;
    if (inZone) classes.at(i) = zoned;
    else if (classes.at(i) < impassable) classes.at(i) = impassable;
  }
  return newlyBlocked;
}

}  // namespace rover
