#pragma once
// An elevation model as the terrain layers read it (SPEC §2): heights in metres on a row-major grid,
// NaN where the source had no data, and the cell spacing in metres. Rasters in a geographic CRS
// (pixel size in degrees) keep their native grid: the east-west spacing then shrinks with latitude,
// so it is given per row, computed by the loader from the CRS's own ellipsoid or sphere.
#include <cmath>
#include <vector>

#include "core/grid/raster.hpp"

namespace rover::terrain {

struct Dem {
  Raster<float> z;  // metres; NaN = nodata
  // Metres per pixel along x for each row; empty when geometry.cellWidth holds everywhere.
  std::vector<double> rowCellWidth;

  const GridGeometry& geometry() const { return z.geometry; }
  double dx(int row) const {
    return rowCellWidth.empty() ? z.geometry.cellWidth : rowCellWidth[row];
  }
  double dy() const { return z.geometry.cellHeight; }
  bool valid(int row, int col) const { return !std::isnan(z(row, col)); }
};

}  // namespace rover::terrain
