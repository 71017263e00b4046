#pragma once
// DEMs from formulas for tests: z(x, y) sampled at the cell centres of the local frame (SPEC §0).
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/terrain/dem.hpp"

namespace rover::test {

inline terrain::Dem demFrom(int rows, int cols, double cell,
                            const std::function<double(double, double)>& z) {
  terrain::Dem d;
  d.z = Raster<float>(GridGeometry{rows, cols, cell, cell}, 0.0f);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      Eigen::Vector2d p = cellToLocal(d.geometry(), {r, c});
      d.z(r, c) = static_cast<float>(z(p.x(), p.y()));
    }
  return d;
}

// A DEM drawn as a picture: one character is one metre (4 × 4 cells of 0.25 m), '#' a 1 m high
// block (a vertical step, so impassable at its edges), anything else flat ground at 0. Row 0 of
// the picture is the north edge (SPEC §0: y north).
inline terrain::Dem demFromPicture(const std::vector<std::string>& picture) {
  const int rows = static_cast<int>(picture.size()), cols = static_cast<int>(picture[0].size());
  return demFrom(rows * 4, cols * 4, 0.25, [&](double x, double y) {
    const int c = std::clamp(static_cast<int>(std::floor(x)), 0, cols - 1);
    const int r = std::clamp(rows - 1 - static_cast<int>(std::floor(y)), 0, rows - 1);
    return picture[r][c] == '#' ? 1.0 : 0.0;
  });
}

}  // namespace rover::test
