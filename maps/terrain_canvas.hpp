#pragma once
// The grid the synthetic terrain generators (synthetic_terrain.cpp) draw on, in the local frame
// (x east, y north, metres from the lower-left corner, SPEC §0) at cell centres.
#include <algorithm>
#include <cmath>

#include "core/grid/raster.hpp"

namespace rover::maps::synthetic {

inline constexpr double kPi = 3.14159265358979323846;

struct Canvas {
  RowMajorMatrix<float>& z;
  int n = 0;
  double cell = 1.0;

  double extent() const { return n * cell; }
  double x(int col) const { return (col + 0.5) * cell; }
  double y(int row) const { return (n - row - 0.5) * cell; }
  // Cells whose centres lie within [x0, x1] × [y0, y1], clipped to the grid; empty when outside.
  struct Box {
    int row0, row1, col0, col1;
    bool empty() const { return row0 > row1 || col0 > col1; }
  };
  Box box(double x0, double x1, double y0, double y1) const {
    auto clampIndex = [this](double v) {
      return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(n)));
    };
    return {std::max(0, clampIndex(std::ceil(n - 0.5 - y1 / cell))),
            std::min(n - 1, clampIndex(std::floor(n - 0.5 - y0 / cell))),
            std::max(0, clampIndex(std::ceil(x0 / cell - 0.5))),
            std::min(n - 1, clampIndex(std::floor(x1 / cell - 0.5)))};
  }
  // Height at the cell nearest to (x, y), clamped into the grid.
  double heightNear(double px, double py) const {
    const double last = n - 1.0;
    const auto col = static_cast<int>(std::clamp(std::floor(px / cell), 0.0, last));
    const auto row = static_cast<int>(std::clamp(std::floor(n - py / cell), 0.0, last));
    return z(row, col);
  }
};

}  // namespace rover::maps::synthetic
