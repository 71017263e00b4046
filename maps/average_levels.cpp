#include "maps/average_levels.hpp"

#include <fcntl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <limits>
#include <utility>

#include "core/common/parallel.hpp"
#include "maps/grid_file.hpp"

namespace rover::maps {

namespace {

// A source window along one side, as GDAL 3.6 computes it (GDALResampleChunk32R_AverageT): the
// cells [first, last), the first and last cells' weights (1 when whole).
struct Window {
  int first = 0, last = 0;
  double firstWeight = 1, lastWeight = 1;
};

Window windowOf(int j, double ratio, int srcSize) {
  Window w;
  const double from = j * ratio, to = (j + 1) * ratio;
  // GDAL's epsilon against numerical noise, kept so the windows are its windows.
  w.first = static_cast<int>(from + 1e-8);
  w.last = static_cast<int>(std::ceil(to - 1e-8));
  if (w.last == w.first) ++w.last;
  if (w.last > srcSize) w.last = srcSize;
  w.firstWeight = (w.last == w.first + 1) ? 1.0 : 1 - (from - w.first);
  w.lastWeight = 1 - (w.last - to);
  return w;
}

}  // namespace

std::pair<int, int> sourceRowsOf(int srcRows, int dstRows, int dstRow0, int n) {
  const double ratio = static_cast<double>(srcRows) / dstRows;
  return {windowOf(dstRow0, ratio, srcRows).first, windowOf(dstRow0 + n - 1, ratio, srcRows).last};
}

void averageLevelRows(const float* src, int srcRow0, int /*srcRowsHeld*/, int srcRows, int srcCols, int dstRows,
                      int dstCols, int dstRow0, int dstRowCount, float* out) {
  const double rx = static_cast<double>(srcCols) / dstCols, ry = static_cast<double>(srcRows) / dstRows;
  std::vector<Window> xs(static_cast<std::size_t>(dstCols));
  for (int j = 0; j < dstCols; ++j) xs[static_cast<std::size_t>(j)] = windowOf(j, rx, srcCols);
  constexpr float kNoData = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < dstRowCount; ++i) {
    const Window y = windowOf(dstRow0 + i, ry, srcRows);
    float* row = out + static_cast<std::size_t>(i) * dstCols;
    for (int j = 0; j < dstCols; ++j) {
      const Window& x = xs[static_cast<std::size_t>(j)];
      double total = 0, totalWeight = 0;
      bool any = false;
      for (int r = y.first; r < y.last; ++r) {
        const float* line = src + static_cast<std::size_t>(r - srcRow0) * srcCols;
        double lineTotal = 0, lineWeight = 0;
        if (const float v = line[x.first]; !std::isnan(v)) {
          any = true;
          lineWeight = x.firstWeight;
          lineTotal = v * x.firstWeight;
        }
        if (x.first + 1 < x.last) {
          for (int c = x.first + 1; c + 1 < x.last; ++c)
            if (const float v = line[c]; !std::isnan(v)) {
              any = true;
              lineWeight += 1;
              lineTotal += v;
            }
          if (const float v = line[x.last - 1]; !std::isnan(v)) {
            any = true;
            lineWeight += x.lastWeight;
            lineTotal += v * x.lastWeight;
          }
        }
        const double wy = r == y.first ? y.firstWeight : r + 1 == y.last ? y.lastWeight : 1.0;
        total += lineTotal * wy;
        totalWeight += lineWeight * wy;
      }
      row[j] = any ? static_cast<float>(total / totalWeight) : kNoData;
    }
  }
}

std::vector<LevelFile> writeAverageLevels(const std::string& gridFile, int rows, int cols, int levels,
                                          const std::string& prefix, unsigned threads) {
  std::vector<LevelFile> out;
  LevelFile from{gridFile, rows, cols};
  // A level that fails part-way (a full disk) takes the levels written before it along: none is
  // left beside the grid for the caller to know of.
  struct RemoveOnThrow {
    std::vector<LevelFile>& written;
    std::string current;
    ~RemoveOnThrow() {
      if (std::uncaught_exceptions() == 0) return;
      for (const LevelFile& l : written) std::remove(l.path.c_str());
      if (!current.empty()) std::remove(current.c_str());
    }
  } cleanup{out, {}};
  // Bands of 64 level rows (about 130 source rows): enough to hand both cores work on the small
  // levels' few bands, small enough that a band of a 20000-column grid is 10 MB.
  constexpr int kBandRows = 64;
  for (int k = 1; k <= levels; ++k) {
    LevelFile to{prefix + std::to_string(k) + ".f32", std::max(1, from.rows / 2), std::max(1, from.cols / 2)};
    cleanup.current = to.path;
    const GridFileHandle in(from.path, O_RDONLY);
    const GridFileHandle dst(to.path, O_WRONLY | O_CREAT | O_TRUNC);
    const double bytes = 4.0 * to.rows * to.cols;
    const std::size_t bands = static_cast<std::size_t>((to.rows + kBandRows - 1) / kBandRows);
    parallelFor(bands, threads, [&](std::size_t b) {
      const int r0 = static_cast<int>(b) * kBandRows, n = std::min(kBandRows, to.rows - r0);
      const auto [s0, s1] = sourceRowsOf(from.rows, to.rows, r0, n);
      std::vector<float> src(static_cast<std::size_t>(s1 - s0) * from.cols), level(static_cast<std::size_t>(n) * to.cols);
      in.read(src.data(), src.size() * sizeof(float), static_cast<std::int64_t>(s0) * from.cols * 4);
      averageLevelRows(src.data(), s0, s1 - s0, from.rows, from.cols, to.rows, to.cols, r0, n, level.data());
      dst.write(level.data(), level.size() * sizeof(float), static_cast<std::int64_t>(r0) * to.cols * 4, bytes);
    });
    out.push_back(to);
    from = to;
  }
  return out;
}

}  // namespace rover::maps
