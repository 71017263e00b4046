#pragma once
// Display grids of a layer rendering (render.cpp): the source raster as it is, or box-downsampled
// when an overview is asked for.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/grid/raster.hpp"

namespace rover::maps {

// Either a view of the source values (no downsampling) or its own downsampled values.
struct DisplayGrid {
  int rows = 0, cols = 0;
  std::vector<float> own;       // downsampled values, or empty
  const float* view = nullptr;  // the source values when not downsampled
  const float* data() const { return own.empty() ? view : own.data(); }
  std::size_t size() const { return std::size_t(rows) * cols; }
  float at(std::size_t i) const { return data()[i]; }
  float at(int r, int c) const { return data()[std::size_t(r) * cols + c]; }
  bool empty() const { return size() == 0; }
};

// Output size: the source size, or scaled so max(rows, cols) == maxSize with the aspect kept.
void displaySize(int rows, int cols, int maxSize, int& outRows, int& outCols);
// Mean of the finite values in each block; NaN when a block has none.
DisplayGrid downsampleMean(const Raster<float>& src, int outRows, int outCols);
// The worst class in each block: the highest code ignoring NoData, NoData only if all are.
// Codes above NoData are not classes and count as NoData.
DisplayGrid downsampleWorstClass(const Raster<std::uint8_t>& src, int outRows, int outCols);

}  // namespace rover::maps
