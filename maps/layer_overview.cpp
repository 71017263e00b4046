#include "maps/layer_overview.hpp"

#include <algorithm>

#include "core/terrain/layers.hpp"

namespace rover::maps {

namespace {

int ceilDiv(int a, int b) { return static_cast<int>((static_cast<long long>(a) + b - 1) / b); }

}  // namespace

int overviewStep(int rows, int cols, int side) {
  const int longest = std::max(rows, cols);
  int step = 1;
  while (side > 0 && ceilDiv(longest, step * 2) >= side) step *= 2;
  // Never more cells than the largest overview's (4096²): a 4096-px overview of an 8000² map
  // would otherwise read the full grid, 64 M cells.
  while (static_cast<long long>(ceilDiv(rows, step)) * ceilDiv(cols, step) > kMaxOverviewLevelCells) step *= 2;
  return step;
}

Image renderOverview(RenderLayer layer, const TileBlocks& source, int rows, int cols, int side) {
  const int step = overviewStep(rows, cols, side);
  const BlockSpan all{0, 0, ceilDiv(rows, step), ceilDiv(cols, step)};
  terrain::Dem dem;
  Raster<float> shade, slope, mass;
  Raster<std::uint8_t> classes;
  RenderInput in;
  switch (layer) {
    case RenderLayer::Elevation:
    case RenderLayer::Hillshade:
      dem = source.dem(step, all);
      shade = terrain::hillshade(dem);
      in.dem = &dem;
      in.hillshade = &shade;
      break;
    case RenderLayer::Slope:
      dem = source.dem(step, all);
      slope = terrain::slopeHorn(dem);
      in.slopeDeg = &slope;
      break;
    case RenderLayer::Traversability:
      classes = source.classes(step, all);
      in.classes = &classes;
      break;
    case RenderLayer::Pdm:
      mass = source.pdm(step, all);
      in.pdm = &mass;
      break;
  }
  RenderOptions options;
  options.maxSize = side;
  return renderLayer(layer, in, options);
}

}  // namespace rover::maps
