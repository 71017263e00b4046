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
// Cost: what a tile reads comes from its TileBlocks: the whole map in memory (TileSource: up to
// (256·step + 2·step)² cells per tile), or a stored map's pyramid (maps/dem_pyramid.hpp: the
// overview of the tile's zoom, about (256 + 2)² cells at any zoom).
#include <cstdint>
#include <vector>

#include "core/terrain/dem.hpp"
#include "maps/render.hpp"
#include "maps/tile_grid.hpp"

namespace rover::maps {

// A rectangle of blocks at a tile's zoom: block rows r0.., columns c0.. (a block is step × step
// cells, aligned on the whole map; the last row/column of blocks may be cut by the map's edge).
struct BlockSpan {
  int r0 = 0, c0 = 0, rows = 0, cols = 0;
};

// Where a tile's blocks come from. Each call answers the blocks of `span` at `step` cells a
// block: dem() their mean heights (NaN where a block has no data) with cell sizes × step and, on
// a geographic map, the mean east-west width of each block row; classes() the worst class of each
// block (NoData where none); pdm() the mean mass. Throws rover::Error (InvalidInput, "layer") when
// the source has no such raster.
class TileBlocks {
 public:
  virtual ~TileBlocks() = default;
  virtual terrain::Dem dem(int step, const BlockSpan& span) const = 0;
  virtual Raster<std::uint8_t> classes(int step, const BlockSpan& span) const = 0;
  virtual Raster<float> pdm(int step, const BlockSpan& span) const = 0;
  // The ramp of elevation or pdm: colourRange of the whole map's raster.
  virtual ColourRange range() const = 0;
};

// The whole map in memory.
struct TileSource {
  const terrain::Dem* dem = nullptr;              // every layer
  const Raster<std::uint8_t>* classes = nullptr;  // traversability (the whole map's classes)
  const Raster<float>* pdm = nullptr;             // pdm (the whole map's probability mass)
  ColourRange range;  // elevation or pdm: colourRange of the whole map's raster
};

// A kTileSize² RGBA tile, transparent beyond the map and where there is no data. Throws
// rover::Error (InvalidInput, "layer") when the raster the layer needs is missing.
Image renderTile(RenderLayer layer, const TileBlocks& source, const TileWindow& window);
Image renderTile(RenderLayer layer, const TileSource& source, const TileWindow& window);

// The tile's values, kTileSize² floats row-major: elevation (m) or slope (degrees); NaN beyond the
// map and where there is no data. Throws rover::Error (InvalidInput, "layer") for other layers.
std::vector<float> tileValues(RenderLayer layer, const TileBlocks& source, const TileWindow& window);
std::vector<float> tileValues(RenderLayer layer, const TileSource& source, const TileWindow& window);

// The blocks of `span` (in `src`'s own cells, blocks counted from its first cell) reduced: the
// mean of the finite values (NaN where none; the values themselves when step is 1), the worst
// class (the highest code below NoData), and the mean east-west cell width of each block row
// times step (empty for a map without per-row widths). What a stored map without overviews and
// the in-memory TileSource both use, so the two give the same tiles.
Raster<float> blockMean(const Raster<float>& src, int step, const BlockSpan& span);
Raster<std::uint8_t> blockWorstClass(const Raster<std::uint8_t>& src, int step, const BlockSpan& span);
std::vector<double> blockRowWidths(const std::vector<double>& rowCellWidth, int rows, int step, const BlockSpan& span);

}  // namespace rover::maps
