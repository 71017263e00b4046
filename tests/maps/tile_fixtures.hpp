#pragma once
// Shared by the tile tests (test_map_tiles.cpp, test_png_encode.cpp): the PDM mass they render
// and the tile source over a DEM, its classes and that mass.
#include <cmath>

#include "core/grid/raster.hpp"
#include "core/terrain/layers.hpp"
#include "maps/map_tiles.hpp"

namespace rover::test {

// A Gaussian bump of mass, exp(−d² / spread) with d in cells from (row, col), over `g`.
inline Raster<float> massBump(const GridGeometry& g, int row, int col, double spread) {
  Raster<float> mass(g, 0.0f);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c)
      mass(r, c) = static_cast<float>(std::exp(-((r - row) * (r - row) + (c - col) * (c - col)) / spread));
  return mass;
}

inline maps::TileSource tileSourceOf(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                     const Raster<float>& mass) {
  maps::TileSource src;
  src.dem = &dem;
  src.classes = &classes;
  src.pdm = &mass;
  return src;
}

}  // namespace rover::test
