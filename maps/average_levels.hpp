#pragma once
// The overview levels of a map's COG (maps/dem_pyramid.hpp), computed here on every core instead of
// by GDAL's COG driver, which computes them on one thread (issue 24). GDAL 3.6's AVERAGE with NaN
// as nodata, in its arithmetic (GDALResampleChunk32R_AverageT's nodata-mask path):
// - level k + 1 from level k (GDAL cascades AVERAGE levels), level 1 from the grid;
// - a level is floor(size / 2) of the one above along each side (at least 1), as the COG driver
//   sizes them;
// - each pixel averages the source window [j·r, (j + 1)·r) for r = source size / level size, the
//   cut cells at its two ends weighted by the part inside (exactly 2 × 2 cells when the size is
//   even), NaN cells left out, NaN when none is left; sums and weights in double, in GDAL's order
//   (row by row: left cell, middle cells, right cell), then rounded to float.
// Deterministic: the same bytes on every run and thread count (each level pixel is computed from
// its whole window, whatever band it falls in).
// GDAL's own levels differ in one respect, on large maps only: where a level's size is odd, GDAL
// also clips a window at the end of each chunk of rows it reads and weights the clipped row above
// 1 (20000 columns: chunks of 8192 grid rows, so level 4's row 511 weights its last source row
// 1.55, not 0.55) — an artifact of its chunking, not a better average. Not reproduced: a map's
// dem.tif is written once at import and never changes (maps are immutable), so a map's tiles are
// always from one set of levels.
// tests/maps/test_dem_pyramid.cpp checks the bytes against GDAL's own levels where it cuts no
// window (small maps, even shapes), and every level against a plain weighted average elsewhere.
#include <string>
#include <vector>

namespace rover::maps {

struct LevelFile {
  std::string path;  // rows × cols little-endian float32, as maps/grid_file.hpp
  int rows = 0, cols = 0;
};

// Writes `levels` levels of the grid file `gridFile` (rows × cols) to `prefix`1.f32, `prefix`2.f32,
// …, on `threads` threads (0: every core), in bands of rows: memory a band of source rows and one
// of level rows per thread (about 130 source rows), never a level whole. Disk: a third of the
// grid's bytes. Throws GridFileError (maps/grid_file.hpp) when a file fails, DiskFull when the
// disk is full; then no level file is left.
std::vector<LevelFile> writeAverageLevels(const std::string& gridFile, int rows, int cols, int levels,
                                          const std::string& prefix, unsigned threads = 0);

// One level's rows [dstRow0, dstRow0 + dstRows) of a `dstCols`-wide level from the source rows
// [srcRow0, srcRow0 + srcRowsHeld) of a srcRows × srcCols grid (`src`, row-major), which must
// hold every source row those level rows read (sourceRowsOf). The arithmetic of the header.
void averageLevelRows(const float* src, int srcRow0, int srcRowsHeld, int srcRows, int srcCols, int dstRows,
                      int dstCols, int dstRow0, int dstRowCount, float* out);

// The source rows [first, last) that level rows [dstRow0, dstRow0 + n) read.
std::pair<int, int> sourceRowsOf(int srcRows, int dstRows, int dstRow0, int n);

}  // namespace rover::maps
