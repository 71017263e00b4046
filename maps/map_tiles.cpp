#include "maps/map_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"

namespace rover::maps {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using Span = BlockSpan;

// The tile's blocks grown by `halo` on each side, clipped to the map.
Span spanOf(const TileWindow& w, int halo) {
  const int r0 = std::max(0, w.blockRow0 - halo), c0 = std::max(0, w.blockCol0 - halo);
  const int r1 = std::min(w.blocksDown, w.blockRow0 + w.blockRows + halo);
  const int c1 = std::min(w.blocksAcross, w.blockCol0 + w.blockCols + halo);
  return {r0, c0, r1 - r0, c1 - c0};
}

// Calls fn(blockRow, blockCol, cellRow, cellCol) for every cell of every block of `s`.
template <class Fn>
void forCells(const GridGeometry& g, int step, const Span& s, Fn&& fn) {
  for (int i = 0; i < s.rows; ++i) {
    const int rBegin = (s.r0 + i) * step, rEnd = std::min(g.rows, rBegin + step);
    for (int r = rBegin; r < rEnd; ++r)
      for (int j = 0; j < s.cols; ++j) {
        const int cBegin = (s.c0 + j) * step, cEnd = std::min(g.cols, cBegin + step);
        for (int c = cBegin; c < cEnd; ++c) fn(i, j, r, c);
      }
  }
}

// Copies the tile's blocks out of `span`-sized pixels (`px` per block, `channels` values each) into
// a kTileSize² tile, each block magnified; the rest of `tile` is left as it was.
// A row of blocks is placed once and its magnified copies are copies of that tile row (no
// division a pixel: placing was a tenth of a cold tile's rendering).
template <class T>
void placeBlocks(const TileWindow& w, const Span& span, const T* blocks, int channels, T* tile) {
  const int m = w.magnify;
  const std::size_t rowValues = std::size_t(w.blockCols) * m * channels;
  for (int i = 0; i < w.blockRows; ++i) {
    const T* from = blocks + (std::size_t(w.blockRow0 + i - span.r0) * span.cols + (w.blockCol0 - span.c0)) * channels;
    T* first = tile + std::size_t(i) * m * kTileSize * channels;
    if (m == 1) {
      std::copy_n(from, rowValues, first);
      continue;
    }
    T* out = first;
    for (int j = 0; j < w.blockCols; ++j, from += channels)
      for (int k = 0; k < m; ++k, out += channels) std::copy_n(from, channels, out);
    for (int k = 1; k < m; ++k) std::copy_n(first, rowValues, first + std::size_t(k) * kTileSize * channels);
  }
}

// The tile of a picture of `span` (one pixel a block).
Image placed(const TileWindow& w, const Span& span, const Image& pic) {
  Image tile;
  tile.width = tile.height = kTileSize;
  tile.rgba.assign(std::size_t(kTileSize) * kTileSize * 4, 0);  // transparent beyond the map
  placeBlocks(w, span, pic.rgba.data(), 4, tile.rgba.data());
  return tile;
}

}  // namespace

Raster<float> blockMean(const Raster<float>& src, int step, const Span& s) {
  const GridGeometry& g = src.geometry;
  Raster<float> out(GridGeometry{s.rows, s.cols, g.cellWidth * step, g.cellHeight * step}, kNaN);
  if (step == 1) {
    out.values = src.values.block(s.r0, s.c0, s.rows, s.cols);
    return out;
  }
  std::vector<double> sum(std::size_t(s.rows) * s.cols, 0.0);
  std::vector<int> count(sum.size(), 0);
  forCells(g, step, s, [&](int i, int j, int r, int c) {
    const float v = src(r, c);
    if (std::isfinite(v)) {
      sum[std::size_t(i) * s.cols + j] += v;
      ++count[std::size_t(i) * s.cols + j];
    }
  });
  for (std::size_t k = 0; k < sum.size(); ++k)
    if (count[k]) out.at(static_cast<int>(k)) = static_cast<float>(sum[k] / count[k]);
  return out;
}

std::vector<double> blockRowWidths(const std::vector<double>& rowCellWidth, int rows, int step, const Span& s) {
  std::vector<double> out;
  if (rowCellWidth.empty()) return out;
  out.resize(s.rows);
  for (int i = 0; i < s.rows; ++i) {
    const int rBegin = (s.r0 + i) * step, rEnd = std::min(rows, rBegin + step);
    double sum = 0;
    for (int r = rBegin; r < rEnd; ++r) sum += rowCellWidth[r];
    out[i] = sum / (rEnd - rBegin) * step;
  }
  return out;
}

Raster<std::uint8_t> blockWorstClass(const Raster<std::uint8_t>& src, int step, const Span& s) {
  constexpr auto kNoData = static_cast<std::uint8_t>(terrain::TerrainClass::NoData);
  const GridGeometry& g = src.geometry;
  Raster<std::uint8_t> out(GridGeometry{s.rows, s.cols, g.cellWidth * step, g.cellHeight * step}, kNoData);
  std::vector<int> worst(std::size_t(s.rows) * s.cols, -1);
  forCells(g, step, s, [&](int i, int j, int r, int c) {
    const int v = src(r, c);
    if (v < kNoData) worst[std::size_t(i) * s.cols + j] = std::max(worst[std::size_t(i) * s.cols + j], v);
  });
  for (std::size_t k = 0; k < worst.size(); ++k)
    if (worst[k] >= 0) out.at(static_cast<int>(k)) = static_cast<std::uint8_t>(worst[k]);
  return out;
}

namespace {

// The whole map in memory as TileBlocks.
class MemoryBlocks final : public TileBlocks {
 public:
  explicit MemoryBlocks(const TileSource& s) : s_(s) {}
  terrain::Dem dem(int step, const Span& span) const override {
    if (s_.dem == nullptr || s_.dem->z.empty())
      throw Error(ErrorCode::InvalidInput, "layer", "the tile needs the DEM");
    terrain::Dem out;
    out.z = blockMean(s_.dem->z, step, span);
    out.rowCellWidth = blockRowWidths(s_.dem->rowCellWidth, s_.dem->geometry().rows, step, span);
    return out;
  }
  Raster<std::uint8_t> classes(int step, const Span& span) const override {
    if (s_.classes == nullptr)
      throw Error(ErrorCode::InvalidInput, "layer", "the traversability tile needs the class raster");
    return blockWorstClass(*s_.classes, step, span);
  }
  Raster<float> pdm(int step, const Span& span) const override {
    if (s_.pdm == nullptr) throw Error(ErrorCode::InvalidInput, "layer", "the pdm tile needs the PDM raster");
    return blockMean(*s_.pdm, step, span);
  }
  ColourRange range() const override { return s_.range; }

 private:
  const TileSource& s_;
};

}  // namespace

Image renderTile(RenderLayer layer, const TileBlocks& source, const TileWindow& w) {
  // Elevation (shaded), hillshade and slope read one block beyond the tile: the 3×3 kernel's halo.
  const bool kernel = layer == RenderLayer::Elevation || layer == RenderLayer::Hillshade || layer == RenderLayer::Slope;
  const Span span = spanOf(w, kernel ? 1 : 0);
  terrain::Dem blocks;
  Raster<float> mass;
  Raster<std::uint8_t> classes;
  RenderInput in;
  if (kernel) {
    blocks = source.dem(w.step, span);
    in.dem = &blocks;
  }
  if (layer == RenderLayer::Elevation) {
    return placed(w, span, renderShadedElevation(blocks, source.range()));  // no hillshade raster
  } else if (layer == RenderLayer::Hillshade) {
    return placed(w, span, renderHillshade(blocks));  // no hillshade raster
  } else if (layer == RenderLayer::Slope) {
    return placed(w, span, renderSlope(blocks));  // no slope raster, few arctangents
  } else if (layer == RenderLayer::Traversability) {
    classes = source.classes(w.step, span);
    in.classes = &classes;
  } else if (layer == RenderLayer::Pdm) {
    mass = source.pdm(w.step, span);
    in.pdm = &mass;
  }
  RenderOptions options;
  options.legend = false;
  const ColourRange range = source.range();
  options.range = &range;
  return placed(w, span, renderLayer(layer, in, options));
}

Image renderTile(RenderLayer layer, const TileSource& source, const TileWindow& w) {
  return renderTile(layer, MemoryBlocks(source), w);
}

std::vector<float> tileValues(RenderLayer layer, const TileBlocks& source, const TileWindow& w) {
  if (layer != RenderLayer::Elevation && layer != RenderLayer::Slope)
    throw Error(ErrorCode::InvalidInput, "layer", "value tiles are elevation or slope");
  const Span span = spanOf(w, layer == RenderLayer::Slope ? 1 : 0);
  const terrain::Dem blocks = source.dem(w.step, span);
  const Raster<float> values = layer == RenderLayer::Slope ? terrain::slopeHorn(blocks) : blocks.z;
  std::vector<float> tile(std::size_t(kTileSize) * kTileSize, kNaN);
  placeBlocks(w, span, values.values.data(), 1, tile.data());
  return tile;
}

std::vector<float> tileValues(RenderLayer layer, const TileSource& source, const TileWindow& w) {
  return tileValues(layer, MemoryBlocks(source), w);
}

}  // namespace rover::maps
