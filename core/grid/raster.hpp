#pragma once
// A row-major grid of values on Eigen with its geometry and, when it came from a georeferenced
// file, the GDAL geotransform and CRS carried along unchanged (SPEC §0). The value type of
// grid_map's layers, reduced to one layer.
#include <Eigen/Core>
#include <array>
#include <string>

#include "core/grid/geometry.hpp"

namespace rover {

struct GeoReference {
  std::array<double, 6> geotransform{0, 1, 0, 0, 0, -1};  // GDAL order
  std::string crsWkt;                                     // "" when unknown
  bool valid = false;
};

template <class T>
using RowMajorMatrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

template <class T>
struct Raster {
  GridGeometry geometry;
  RowMajorMatrix<T> values;
  GeoReference geo;

  Raster() = default;
  Raster(GridGeometry g, T fill) : geometry(g), values(g.rows, g.cols) { values.setConstant(fill); }

  T& operator()(int row, int col) { return values(row, col); }
  const T& operator()(int row, int col) const { return values(row, col); }
  T& at(int index) { return values.data()[index]; }
  const T& at(int index) const { return values.data()[index]; }
  bool empty() const { return geometry.cellCount() == 0; }
};

}  // namespace rover
