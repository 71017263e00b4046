#pragma once
// A stored map as tiled, overviewed rasters (issue 24), so a tile at any zoom reads about 256²
// cells (plus its halo) whatever the map's size:
// - dem.tif, the elevation as a Cloud-Optimised GeoTIFF (GDAL's COG driver): 128² internal tiles
//   (a tile's 258² window with its halo decodes 16 of them, 1 MiB, where 256² tiles made it 9,
//   2.3 MiB; maps stored with 256² tiles read the same),
//   ZSTD with horizontal differencing (lossless), NaN as nodata, and one overview per
//   zoom below the tile grid's native zoom, each GDAL's AVERAGE over 2^k × 2^k cells: the blocks
//   of zoom native − k (maps/tile_grid.hpp), except that the driver rounds a level's size down
//   (floor(size / 2^k) where the grid has ceil), so a level's pixels drift by up to one cell
//   of the full grid across the map and a cut last block reads its neighbour.
// - classes.tif, the traversability classes (uint8, tiled, ZSTD) with internal overviews of exactly the
//   grid's blocks (ceil sizes) filled with the worst class of each block, computed exactly (the
//   worst of the worst is the worst, level by level).
// The readers answer a tile's blocks (maps/map_tiles.hpp BlockSpan) from the level of its zoom; a
// file without that level (a map stored before the pyramid: a tiled GeoTIFF without overviews) is
// read at full resolution over the blocks' cells and reduced the way the in-memory tiles are
// (blockMean, blockWorstClass), so old maps keep giving the same tiles, only slower.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/terrain/dem.hpp"
#include "maps/dem_io.hpp"
#include "maps/map_tiles.hpp"

namespace rover::maps {

// Writes `dem` as the map's COG, atomically (PATH.tmp, then rename). Memory: the COG driver reads
// `dem` in place (a MEM dataset over its cells, no copy) plus GDAL's block cache; disk: while it
// writes, a temporary uncompressed overview file next to it (4·N/3 bytes for N cells: a third of
// the float grid). A full disk throws DiskFull.
void writeDemCog(const std::string& path, const Raster<float>& dem);
// The same COG from a grid file (maps/grid_file.hpp) of `g`'s shape, read through
// GDAL as a raw band, its overview levels computed on every core (maps/average_levels.hpp) and
// handed to the driver as the source's own: memory is a band of rows per thread, GDAL's block
// cache and the driver's buffers, not the grid; disk while it writes, the levels' raw files next
// to the grid (4·N/3 bytes, removed before it returns). Byte for byte the in-memory writer's COG
// except, on large maps with odd level sizes, in the level rows where GDAL's own chunking clips a
// window (maps/average_levels.hpp).
void writeDemCog(const std::string& path, const std::string& gridFile, const GridGeometry& g, const GeoReference& geo);

// A map's elevation stored raw, readable before its COG is written (issue 24: the first tiles of a
// 300 M-cell map within 20 s): the overview levels of `gridFile` (the float32 grid of `g`'s
// shape, maps/grid_file.hpp) computed on every core as raw files next to `vrtPath`
// (STEM-1.f32, STEM-1.f32.vrt, …), and `vrtPath`, a GDAL VRT with a raw band over the grid, the
// levels as its overviews, the georeferencing and NaN nodata writeDemCog gives the COG. Every
// GDAL reader opens it as it opens that COG: the same sizes, values and overviews (the COG is
// written from it, writeDemCogFromRaw), so a tile is the same bytes from either. Paths inside
// are relative to the VRT's folder, which may move. Returns the files it wrote, `vrtPath` last
// (the grid is the caller's). Memory: a band of rows per thread; disk: a third of the grid's
// bytes. Throws GridFileError, DiskFull.
std::vector<std::string> writeRawDem(const std::string& vrtPath, const std::string& gridFile, const GridGeometry& g,
                                     const GeoReference& geo);
// The COG at `path` (atomically, as writeDemCog) from a raw DEM's VRT (writeRawDem), its levels
// compressed as they are. `cancelled`, polled while the driver writes, stops it: nothing is left
// behind and std::runtime_error is thrown. Memory: GDAL's block cache and the driver's buffers;
// disk: the COG as it grows (the driver uses the levels, it writes no overview file of its own).
void writeDemCogFromRaw(const std::string& path, const std::string& vrtPath,
                        const std::function<bool()>& cancelled = {});

// A PDM's probability mass on its map's grid as the same kind of COG (its overviews are each
// block's mean mass, what a pdm tile below the native zoom shows), with the top of its colour ramp
// (the largest mass of the full-resolution grid, colourRange(Pdm, mass)) in the file's metadata:
// a pdm tile then reads its window and the ramp, never the whole mass. Memory and disk as
// writeDemCog's.
void writeMassCog(const std::string& path, const Raster<float>& mass, const ColourRange& range);

// Writes the class pyramid, atomically. Memory: the levels below full resolution (a third of
// `classes`' bytes). A full disk throws DiskFull.
void writeClassPyramid(const std::string& path, const Raster<std::uint8_t>& classes);

// The mean heights of `span`'s blocks of `step` × step cells of the stored DEM at `path` (whose
// header is `header`, read once per map with readDemHeader): cell sizes × step, a geographic
// map's block-row widths, NaN where a block has no data (an all-nodata window is no error).
// Throws std::runtime_error when the stored file does not read (the server's fault, not a
// request's).
terrain::Dem readDemBlocks(const std::string& path, const DemHeader& header, int step, const BlockSpan& span);

// The worst class of `span`'s blocks of the stored class pyramid at `path`.
Raster<std::uint8_t> readClassBlocks(const std::string& path, int step, const BlockSpan& span);

// readDemBlocks and readClassBlocks keep a few open handles per stored file (a file rewritten at
// the same path is opened afresh). Closes those of the files under `dir` (a deleted map's folder),
// so their disk space is freed now.
void forgetStoredRasters(const std::string& dir);

// A stored map's tiles (elevation, hillshade, slope, traversability) drawn from its pyramid:
// `demPath` (the COG, or an older tiled GeoTIFF), `classPath` (the class pyramid), the DEM's
// header (readDemHeader, once per map) and the map's ramp (fixed at import). No PDM: pdm() throws
// rover::Error (InvalidInput, "layer").
class PyramidBlocks final : public TileBlocks {
 public:
  PyramidBlocks(std::string demPath, std::string classPath, std::shared_ptr<const DemHeader> header,
                ColourRange range)
      : dem_(std::move(demPath)), classes_(std::move(classPath)), header_(std::move(header)), range_(range) {}
  terrain::Dem dem(int step, const BlockSpan& span) const override;
  Raster<std::uint8_t> classes(int step, const BlockSpan& span) const override;
  Raster<float> pdm(int step, const BlockSpan& span) const override;
  ColourRange range() const override { return range_; }

 private:
  std::string dem_, classes_;
  std::shared_ptr<const DemHeader> header_;
  ColourRange range_;
};

// A PDM's tiles drawn from its mass COG (writeMassCog) on a map of `geometry` (the map's grid,
// from its stored header): pdm() reads the level of the tile's zoom, range() is the ramp stored
// with it (read when constructed). No DEM or classes: dem() and classes() throw rover::Error
// (InvalidInput, "layer"). Throws std::runtime_error when the file does not read or carries no
// ramp (the server's file, not a request's fault).
class MassPyramidBlocks final : public TileBlocks {
 public:
  MassPyramidBlocks(std::string path, const GridGeometry& geometry);
  terrain::Dem dem(int step, const BlockSpan& span) const override;
  Raster<std::uint8_t> classes(int step, const BlockSpan& span) const override;
  Raster<float> pdm(int step, const BlockSpan& span) const override;
  ColourRange range() const override { return range_; }

 private:
  std::string path_;
  DemHeader header_;
  ColourRange range_;
};

// What a stored raster's layout is (gdalinfo's "Image Structure" and overview list): for tests,
// the benchmark and GET /api/maps/{id}.
struct PyramidInfo {
  int rows = 0, cols = 0;
  int blockWidth = 0, blockHeight = 0;
  std::vector<std::pair<int, int>> overviews;  // cols × rows of each, largest first
  std::string compression;                     // DEFLATE, ZSTD, …, "" when none
  std::string layout;                          // "COG" for a Cloud-Optimised GeoTIFF
};
PyramidInfo pyramidInfo(const std::string& path);

}  // namespace rover::maps
