#include "core/coverage/terrain_world.hpp"

#include <cmath>

namespace rover::coverage {

World worldFromDem(const terrain::Dem& dem, const terrain::TraversabilityParams& params) {
  terrain::Traversability t = terrain::traversability(dem, params);
  const GridGeometry& g = dem.geometry();
  World w;
  w.obstacles = Raster<std::uint8_t>(g, 0);
  w.obstacles.geo = dem.z.geo;
  w.heights = Raster<double>(g, 0.0);
  w.heights.geo = dem.z.geo;
  for (int i = 0; i < g.cellCount(); ++i) {
    auto c = static_cast<terrain::TerrainClass>(t.classes.at(i));
    w.obstacles.at(i) = c == terrain::TerrainClass::Impassable || c == terrain::TerrainClass::NoData;
    float z = dem.z.at(i);
    w.heights.at(i) = std::isnan(z) ? 0.0 : z;  // never read: obstacles are never entered
  }
  return w;
}

}  // namespace rover::coverage
