#pragma once
// The pixels of one tile (tile_grid.hpp) of a map's layer (issue 24): rendered from a window of the
// map's rasters with the halo a 3×3 kernel needs, so slope and hillshade at a tile's edge are the
// values the whole-map computation gives (no seams), and with the map's own colour range, so
// adjacent tiles match. At the native zoom a tile is byte for byte the crop of renderLayer's
// full-size picture (without legend).
// Below the native zoom the elevation is box-averaged over each block (mean of its cells with
// data), and slope and hillshade are computed on those block means (a coarser DEM: the slope of the
// ground at the scale shown, not the mean of finer slopes); classes take the worst class in the
// block, a PDM the mean mass. Past the native zoom each cell is repeated (nearest neighbour).
// Cost: reads (256·step + 2·step)² cells at most, whatever the map's size.
#include <cstdint>
#include <vector>

#include "core/terrain/dem.hpp"
#include "maps/render.hpp"
#include "maps/tile_grid.hpp"

namespace rover::maps {

struct TileSource {
  const terrain::Dem* dem = nullptr;              // every layer
  const Raster<std::uint8_t>* classes = nullptr;  // traversability (the whole map's classes)
  const Raster<float>* pdm = nullptr;             // pdm (the whole map's probability mass)
  ColourRange range;  // elevation or pdm: colourRange of the whole map's raster
};

// A kTileSize² RGBA tile, transparent beyond the map and where there is no data. Throws
// rover::Error (InvalidInput, "layer") when the raster the layer needs is missing.
Image renderTile(RenderLayer layer, const TileSource& source, const TileWindow& window);

// The tile's values, kTileSize² floats row-major: elevation (m) or slope (degrees); NaN beyond the
// map and where there is no data. Throws rover::Error (InvalidInput, "layer") for other layers.
std::vector<float> tileValues(RenderLayer layer, const TileSource& source, const TileWindow& window);

}  // namespace rover::maps
