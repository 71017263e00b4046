#include "maps/tile_grid.hpp"

#include <algorithm>

namespace rover::maps {

namespace {

int ceilDiv(long long a, long long b) { return static_cast<int>((a + b - 1) / b); }

// Blocks of the whole map along a side of `cells` cells at zoom z.
int blocksAlong(const TileGrid& g, int cells, int z) {
  return z <= g.nativeZoom ? ceilDiv(cells, 1LL << (g.nativeZoom - z)) : cells;
}

// Tile pixels per block at zoom z (1 up to the native zoom).
int magnifyAt(const TileGrid& g, int z) { return z <= g.nativeZoom ? 1 : 1 << (z - g.nativeZoom); }

}  // namespace

TileGrid tileGridOf(int rows, int cols) {
  TileGrid g{std::max(1, rows), std::max(1, cols), 0};
  while ((static_cast<long long>(kTileSize) << g.nativeZoom) < std::max(g.rows, g.cols)) ++g.nativeZoom;
  return g;
}

int tilesAcross(const TileGrid& g, int z) {
  return ceilDiv(static_cast<long long>(blocksAlong(g, g.cols, z)) * magnifyAt(g, z), kTileSize);
}

int tilesDown(const TileGrid& g, int z) {
  return ceilDiv(static_cast<long long>(blocksAlong(g, g.rows, z)) * magnifyAt(g, z), kTileSize);
}

std::optional<TileWindow> tileWindow(const TileGrid& g, long long z, long long x, long long y) {
  if (z < 0 || z > g.maxZoom() || x < 0 || y < 0) return std::nullopt;
  const int zi = static_cast<int>(z);
  if (x >= tilesAcross(g, zi) || y >= tilesDown(g, zi)) return std::nullopt;
  TileWindow w;
  w.z = zi;
  w.x = static_cast<int>(x);
  w.y = static_cast<int>(y);
  w.step = zi <= g.nativeZoom ? 1 << (g.nativeZoom - zi) : 1;
  w.magnify = magnifyAt(g, zi);
  w.blocksDown = blocksAlong(g, g.rows, zi);
  w.blocksAcross = blocksAlong(g, g.cols, zi);
  const int perTile = kTileSize / w.magnify;  // blocks along a tile's side
  w.blockRow0 = w.y * perTile;
  w.blockCol0 = w.x * perTile;
  w.blockRows = std::min(perTile, w.blocksDown - w.blockRow0);
  w.blockCols = std::min(perTile, w.blocksAcross - w.blockCol0);
  return w;
}

}  // namespace rover::maps
