#include "maps/display_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/terrain/layers.hpp"

namespace rover::maps {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Block boundaries: output index i covers source [edges[i], edges[i + 1]); never empty because
// out <= n.
std::vector<int> blockEdges(int n, int out) {
  std::vector<int> e(out + 1);
  for (int i = 0; i <= out; ++i) e[i] = static_cast<int>(std::int64_t(i) * n / out);
  return e;
}

}  // namespace

void displaySize(int rows, int cols, int maxSize, int& outRows, int& outCols) {
  outRows = rows;
  outCols = cols;
  if (maxSize <= 0 || std::max(rows, cols) <= maxSize) return;
  if (cols >= rows) {
    outCols = maxSize;
    outRows = std::clamp(static_cast<int>(std::lround(double(rows) * maxSize / cols)), 1, maxSize);
  } else {
    outRows = maxSize;
    outCols = std::clamp(static_cast<int>(std::lround(double(cols) * maxSize / rows)), 1, maxSize);
  }
}

DisplayGrid downsampleMean(const Raster<float>& src, int outRows, int outCols) {
  const int rows = src.geometry.rows, cols = src.geometry.cols;
  if (outRows == rows && outCols == cols) return DisplayGrid{rows, cols, {}, src.values.data()};
  DisplayGrid g{outRows, outCols, std::vector<float>(std::size_t(outRows) * outCols), nullptr};
  const auto re = blockEdges(rows, outRows), ce = blockEdges(cols, outCols);
  std::vector<double> sum(outCols);
  std::vector<int> count(outCols);
  for (int i = 0; i < outRows; ++i) {
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(count.begin(), count.end(), 0);
    for (int r = re[i]; r < re[i + 1]; ++r) {
      const float* row = src.values.data() + std::size_t(r) * cols;
      for (int j = 0; j < outCols; ++j)
        for (int c = ce[j]; c < ce[j + 1]; ++c)
          if (std::isfinite(row[c])) {
            sum[j] += row[c];
            ++count[j];
          }
    }
    for (int j = 0; j < outCols; ++j)
      g.own[std::size_t(i) * outCols + j] = count[j] ? static_cast<float>(sum[j] / count[j]) : kNaN;
  }
  return g;
}

DisplayGrid downsampleWorstClass(const Raster<std::uint8_t>& src, int outRows, int outCols) {
  const int rows = src.geometry.rows, cols = src.geometry.cols;
  constexpr int kNoData = static_cast<int>(terrain::TerrainClass::NoData);
  const auto re = blockEdges(rows, outRows), ce = blockEdges(cols, outCols);
  DisplayGrid g{outRows, outCols, std::vector<float>(std::size_t(outRows) * outCols), nullptr};
  std::vector<int> worst(outCols);
  for (int i = 0; i < outRows; ++i) {
    std::fill(worst.begin(), worst.end(), -1);
    for (int r = re[i]; r < re[i + 1]; ++r) {
      const std::uint8_t* row = src.values.data() + std::size_t(r) * cols;
      for (int j = 0; j < outCols; ++j)
        for (int c = ce[j]; c < ce[j + 1]; ++c)
          if (row[c] < kNoData) worst[j] = std::max(worst[j], int(row[c]));
    }
    for (int j = 0; j < outCols; ++j)
      g.own[std::size_t(i) * outCols + j] = static_cast<float>(worst[j] < 0 ? kNoData : worst[j]);
  }
  return g;
}

}  // namespace rover::maps
