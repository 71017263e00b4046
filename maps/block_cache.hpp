#pragma once
// Decoded blocks of the stored tiled rasters (dem.tif, classes.tif, a PDM's mass COG), shared by
// every open handle of a file (issue 24: cold tiles). The tile readers keep a few handles per file
// (maps/dem_pyramid.cpp, one per thread at a time) and GDAL's block cache keys its blocks by
// handle, so a 256² ZSTD block was decompressed again by each handle that needed it; and a tile
// with its one-cell halo touches 3 × 3 blocks, so neighbouring tiles and the elevation, hillshade
// and slope tiles of one address share most of theirs. ZSTD and libtiff's predictor were 28 % of the
// server's CPU serving cold tiles of a 7000² map (perf, 16 clients).
// A block is decoded once (GDALReadBlock: the driver's own decoding, outside GDAL's block cache)
// into this cache and windows are copied out of it, so a window's values are exactly what
// GDALRasterIO gives (same type, one cell a pixel: a copy out of the same decoded blocks).
// Memory: at most kDecodedBlockBytes of blocks (least recently used dropped first), a few spare
// buffers, and each block in use by a reader until its copy ends. The cap is small on purpose: a
// dropped block's buffer takes the next decode, so a full cache decodes into pages already
// resident, where a large one kept faulting fresh pages in (zeroed by the kernel, charged to the
// cgroup) on every cold tile while it grew: on a 7000² map 128 cold tiles decoded 65 MiB, and
// the page faults were 13 % of the server's CPU with a 128 MiB cap. 32 MiB holds 512 blocks of
// 128² floats, the blocks of 32 tiles with their halos: a screen of tiles and their neighbours.
#include <gdal.h>
#include <sys/stat.h>

#include <cstddef>
#include <string>

namespace rover::maps {

constexpr std::size_t kDecodedBlockBytes = std::size_t(32) << 20;

// Copies the window (c0, r0, cols × rows, inside the band) of `band`, a band (or overview) of
// `ds`, the file at `path` known as `id` (stat: a file rewritten at the same path is another file), into
// `out` (cols × rows values of `type`, row-major) through the shared blocks. Returns false, having
// read nothing, when the band is not one the cache takes (not a tiled GeoTIFF band of `type`, or
// blocks over 4 MiB): read it with GDALRasterIO. Throws std::runtime_error when a block does not
// read.
bool readThroughBlocks(GDALDatasetH ds, GDALRasterBandH band, const std::string& path, const struct stat& id, int c0, int r0, int cols,
                       int rows, void* out, GDALDataType type);

// Drops the blocks of the files under `dir` (a deleted map's folder: its memory is freed now).
void forgetDecodedBlocks(const std::string& dir);

}  // namespace rover::maps
