#pragma once
// The tile pyramid of a map (issue 24): square tiles of 256 px in the map's own grid, rows and
// columns counted from the top-left. Zoom 0 shows the whole map in one tile; the native zoom is
// the smallest at which one DEM cell is one tile pixel; two zooms past it magnify cells (2×2 and
// 4×4 pixels). Below the native zoom a tile pixel shows a block of step × step cells (step = 2^
// (native − z)), blocks aligned on the whole map so every tile of a zoom cuts the same blocks.
// Pure arithmetic: addressing only, no pixels.
#include <optional>

namespace rover::maps {

constexpr int kTileSize = 256;
constexpr int kTileZoomsPastNative = 2;

struct TileGrid {
  int rows = 0, cols = 0;  // the map's cells
  int nativeZoom = 0;      // one cell per tile pixel
  int maxZoom() const { return nativeZoom + kTileZoomsPastNative; }
};

// The grid of a rows × cols map (both >= 1).
TileGrid tileGridOf(int rows, int cols);

// What one tile shows: blocks of `step` × `step` cells (the last row/column of blocks may be cut
// by the map's edge), each drawn as `magnify` × `magnify` tile pixels; one of step and magnify is 1.
struct TileWindow {
  int z = 0, x = 0, y = 0;
  int step = 1;                    // cells per block along each side
  int magnify = 1;                 // tile pixels per block along each side
  int blocksDown = 0, blocksAcross = 0;  // blocks of the whole map at this zoom
  int blockRow0 = 0, blockCol0 = 0;      // the tile's first block
  int blockRows = 0, blockCols = 0;      // blocks inside the map (the tile's pixels beyond are empty)
};

// The tile z/x/y of `grid`; nullopt when z is outside [0, maxZoom] or x/y outside the zoom's
// tiles (negative or huge values included: long long so a client's number is never narrowed first).
std::optional<TileWindow> tileWindow(const TileGrid& grid, long long z, long long x, long long y);

// Tiles across and down at zoom z (z in [0, maxZoom]).
int tilesAcross(const TileGrid& grid, int z);
int tilesDown(const TileGrid& grid, int z);

}  // namespace rover::maps
