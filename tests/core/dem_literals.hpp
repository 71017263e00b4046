#pragma once
// DEMs from formulas for tests: z(x, y) sampled at the cell centres of the local frame (SPEC §0).
#include <functional>

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

}  // namespace rover::test
