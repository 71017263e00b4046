#pragma once
// Colourised PNG renderings of terrain layers with a legend (issue: terrain layers, exports):
// hillshaded elevation, hillshade, slope, traversability classes, PDM. Encoded in memory
// (maps/png_encode.cpp), so the server can answer with the bytes and the CLI can write them.
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/terrain/dem.hpp"

namespace rover::maps {

enum class RenderLayer { Elevation, Hillshade, Slope, Traversability, Pdm };
// "elevation" | "hillshade" | "slope" | "traversability" | "pdm"; throws rover::Error otherwise.
RenderLayer renderLayerFromName(const std::string& name);
// The inverse: the layer's name as renderLayerFromName takes it.
const char* renderLayerName(RenderLayer layer);

// The rasters a rendering may need; only the ones its layer uses must be set.
struct RenderInput {
  const terrain::Dem* dem = nullptr;                // Elevation
  const Raster<float>* hillshade = nullptr;         // Elevation (shading), Hillshade
  const Raster<float>* slopeDeg = nullptr;          // Slope
  const Raster<std::uint8_t>* classes = nullptr;    // Traversability (terrain::TerrainClass)
  const Raster<float>* pdm = nullptr;               // Pdm (probability mass per cell)
};

// The values a colour ramp spans (elevation: 2nd–98th percentile; PDM: 0 to the largest mass).
struct ColourRange {
  double lo = 0, hi = 1;
};
// The range renderLayer gives `layer` when it draws all of `values` at full size: tiles take it
// from the whole map (map_tiles.hpp), so every tile of a map uses one ramp and adjacent tiles
// match. Hillshade, slope and classes have fixed scales and ignore it.
ColourRange colourRange(RenderLayer layer, const Raster<float>& values);

// colourRange(Elevation, …) of a grid of `cells` heights seen in pieces (a map import streams
// them): add() each piece with the index of its first cell, in any order, then range(). When
// every sampled cell was nodata on a sparse grid, needsEveryCell() asks for two more passes over
// all the cells, in order, as colourRange takes them: countFinite() over each piece, then
// addEvery() over each piece, which keeps every k-th finite height (again at most ~1M: a grid of
// nodata on the fixed stride must not make the sample a full-size copy).
class ElevationSample {
 public:
  explicit ElevationSample(std::size_t cells);
  void add(std::size_t first, const float* values, std::size_t n);
  bool needsEveryCell() const { return heights_.empty() && stride_ > 1 && !every_; }
  void countFinite(const float* values, std::size_t n);
  void addEvery(const float* values, std::size_t n);
  ColourRange range();

 private:
  std::size_t stride_;
  bool every_ = false;
  std::size_t finite_ = 0;      // finite cells counted by countFinite
  std::size_t finiteSeen_ = 0;  // finite cells addEvery has passed
  std::vector<float> heights_;
};

struct RenderOptions {
  int maxSize = 0;      // > 0: downsample (box average) so neither side exceeds it — an overview
  bool legend = true;   // a legend strip with title, colour bar / class swatches and values
  int legendScale = 1;  // > 1: the legend drawn that many times larger (a big picture's labels)
  const ColourRange* range = nullptr;  // set: this ramp range instead of the drawn grid's own
};

// RGBA image, row-major, 4 bytes a pixel; nodata cells are transparent. With a legend, the map
// sits at the top-left and the legend strip (opaque) below it; when the map is narrower than the
// legend's minimum width the area right of the map is transparent.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
};

// Throws rover::Error (InvalidInput, field "layer") when the raster the layer needs is missing or
// empty, (InvalidInput, field "hillshade") when the shading raster does not match the DEM.
Image renderLayer(RenderLayer layer, const RenderInput& input, const RenderOptions& options = {});
// renderLayer(Slope, {slopeDeg = terrain::slopeHorn(dem)}, {legend = false}), pixel for pixel, drawn
// from Horn's sums without the slope raster and, for most cells, without an arctangent (a tile's
// slope: map_tiles.cpp). Throws as renderLayer when the DEM is empty.
Image renderSlope(const terrain::Dem& dem);
// renderLayer(Elevation, {dem, hillshade = terrain::hillshade(dem)}, {legend = false, range}), pixel
// for pixel, in one pass without the hillshade raster (a tile's elevation: map_tiles.cpp).
Image renderShadedElevation(const terrain::Dem& dem, const ColourRange& range);
// renderLayer(Hillshade, {hillshade = terrain::hillshade(dem)}, {legend = false}), pixel for pixel,
// without the hillshade raster (a tile's hillshade: map_tiles.cpp).
Image renderHillshade(const terrain::Dem& dem);
// PNG bytes (every row filtered "Up", deflate level 1: maps/png_encode.cpp): 8-bit RGBA, or with
// Smallest the fewest bytes a pixel that decode to the same RGBA (grey, a palette, RGB, RGBA; what
// tiles use). Throws rover::Error (InvalidInput, field "image") for an image whose buffer does not
// match its size.
enum class PngColours { Rgba, Smallest };
std::vector<std::uint8_t> encodePng(const Image& image, PngColours colours = PngColours::Rgba);

}  // namespace rover::maps
