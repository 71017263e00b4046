#pragma once
// Tiny literal worlds for tests: '.' free, '#' obstacle; optional heights per cell.
#include <string>
#include <vector>

#include "core/coverage/coverage_planner.hpp"

namespace rover::test {

inline coverage::World worldFrom(const std::vector<std::string>& rows, double cell = 1.0) {
  GridGeometry g{static_cast<int>(rows.size()), static_cast<int>(rows[0].size()), cell, cell};
  coverage::World w;
  w.obstacles = Raster<std::uint8_t>(g, 0);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) w.obstacles(r, c) = rows[r][c] == '#';
  return w;
}

inline void setHeights(coverage::World& w, const std::vector<std::vector<double>>& h) {
  w.heights = Raster<double>(w.geometry(), 0.0);
  for (int r = 0; r < w.geometry().rows; ++r)
    for (int c = 0; c < w.geometry().cols; ++c) w.heights(r, c) = h[r][c];
}

inline int idx(const coverage::World& w, int row, int col) {
  return w.geometry().index(row, col);
}

// Direction codes: 0 = E, 1 = NE, 2 = N, 3 = NW, 4 = W, 5 = SW, 6 = S, 7 = SE.
inline coverage::StartCell at(const coverage::World& w, int row, int col, int heading) {
  return {idx(w, row, col), heading};
}

inline CellIndex cellOf(const coverage::World& w, int index) {
  return w.geometry().cell(index);
}

// A table whose only preference is the order given (lower = preferred), for rule tests.
inline coverage::CoverageParams withTable(std::vector<double> relative) {
  coverage::CoverageParams p;
  p.pattern = "custom";
  p.costTable = std::move(relative);
  return p;
}

}  // namespace rover::test
