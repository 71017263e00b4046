#include "maps/render.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/display_grid.hpp"
#include "maps/layer_legend.hpp"
#include "maps/painter.hpp"

namespace rover::maps {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Colour ramps: piecewise linear in RGB between hand-picked stops (position, r, g, b).

struct Stop {
  double at, r, g, b;
};

// Hypsometric tints, low to high: dark green, olive, sand, brown, near-white.
constexpr Stop kHypsometric[] = {{0.00, 38, 115, 77},
                                 {0.25, 134, 166, 84},
                                 {0.50, 224, 204, 128},
                                 {0.75, 168, 112, 66},
                                 {1.00, 245, 240, 232}};
// Slope in degrees: green below the high-risk threshold (10°), yellow at it, orange at the
// impassable threshold (15°), red, dark red at 45°. Hue falls monotonically (ever redder).
constexpr Stop kSlope[] = {{0, 46, 158, 74},
                           {10, 245, 222, 60},
                           {15, 242, 140, 40},
                           {30, 208, 38, 34},
                           {45, 110, 12, 22}};
// Perceptually ordered (luminance rises monotonically: ~28, 84, 123, 173, 220), viridis-like:
// indigo, blue, teal, green, yellow. Our own stops, not matplotlib's table.
constexpr Stop kPerceptual[] = {{0.00, 48, 18, 74},
                                {0.25, 45, 90, 145},
                                {0.50, 30, 150, 135},
                                {0.75, 110, 200, 90},
                                {1.00, 245, 230, 50}};

template <std::size_t N>
Rgba rampColour(const Stop (&stops)[N], double v) {
  if (!(v > stops[0].at)) return {static_cast<std::uint8_t>(stops[0].r),
                                  static_cast<std::uint8_t>(stops[0].g),
                                  static_cast<std::uint8_t>(stops[0].b), 255};
  std::size_t i = 1;
  while (i < N - 1 && v > stops[i].at) ++i;
  const Stop& a = stops[i - 1];
  const Stop& b = stops[i];
  const double t = std::clamp((v - a.at) / (b.at - a.at), 0.0, 1.0);
  // x + (y − x)·t lies in [0, 255]: adding ½ and truncating rounds it as lround does, without
  // the library call per channel of every pixel of every tile.
  auto mix = [t](double x, double y) { return static_cast<std::uint8_t>(x + (y - x) * t + 0.5); };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b), 255};
}

// Traversability classes, indexed by terrain::TerrainClass. NoData is drawn dark grey and
// half-transparent: visibly "not drivable" (SPEC §2) yet distinct from the impassable red.
constexpr Rgba kClassColours[4] = {
    {50, 170, 80, 255}, {255, 176, 0, 255}, {215, 35, 35, 255}, {40, 40, 40, 160}};

// Hillshade of flat ground at the default sun altitude, 255·sin(45°): shading by s / kNeutralShade
// keeps flat terrain at its tint; missing shade (borders, nodata neighbours) is neutral.
constexpr double kNeutralShade = 180.3;

// ---------------------------------------------------------------------------------------------

// The raster a layer draws; InvalidInput on field "layer" when it is missing or empty.
template <class T>
const Raster<T>& required(RenderLayer layer, const Raster<T>* r, const char* what) {
  const std::string name = renderLayerName(layer);
  if (r == nullptr)
    throw Error(ErrorCode::InvalidInput, "layer",
                "layer '" + name + "' needs the " + what + ", which is not available");
  if (r->empty())
    throw Error(ErrorCode::InvalidInput, "layer", "layer '" + name + "' got an empty " + what);
  return *r;
}

// Rounded to the nearest byte, half away from zero as lround; NaN and below 0 → 0.
std::uint8_t toByte(double v) { return v > 0 ? static_cast<std::uint8_t>(std::min(v, 255.0) + 0.5) : 0; }

// Each layer's colour of a value, written once for its legend and its pixels (a tile and the
// legend beside it must agree). Elevation: the hypsometric tint over [lo, lo + span].
Rgba elevationTint(double v, double lo, double span) { return rampColour(kHypsometric, (v - lo) / span); }
Rgba hillshadeGrey(double v) {
  const auto g = toByte(v);
  return Rgba{g, g, g, 255};
}
Rgba slopeColour(double degrees) { return rampColour(kSlope, degrees); }
Rgba massColour(double v, double hi) { return rampColour(kPerceptual, v / hi); }

}  // namespace

// Percentiles from at most ~1M cells: a fixed stride through the grid, so deterministic; a colour
// scale needs no more precision, and a full-size 4096² DEM stays fast.
ElevationSample::ElevationSample(std::size_t n) : stride_(std::max<std::size_t>(1, n >> 20)) {
  heights_.reserve(n / stride_ + 1);
}

void ElevationSample::add(std::size_t first, const float* v, std::size_t n) {
  for (std::size_t i = (stride_ - first % stride_) % stride_; i < n; i += stride_)
    if (std::isfinite(v[i])) heights_.push_back(v[i]);
}

void ElevationSample::countFinite(const float* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) finite_ += std::isfinite(v[i]);
}

void ElevationSample::addEvery(const float* v, std::size_t n) {  // a sparse DEM the stride missed
  every_ = true;
  const std::size_t stride = std::max<std::size_t>(1, finite_ >> 20);
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(v[i]) && finiteSeen_++ % stride == 0) heights_.push_back(v[i]);
}

ColourRange ElevationSample::range() {
  std::vector<float>& h = heights_;
  double lo = 0, hi = 0;
  if (!h.empty()) {  // 2nd and 98th percentiles (nearest rank) clip outliers and spikes
    auto pct = [&](double q) {
      auto it = h.begin() + static_cast<std::ptrdiff_t>(std::lround(q * (h.size() - 1)));
      std::nth_element(h.begin(), it, h.end());
      return double(*it);
    };
    lo = pct(0.02);
    hi = pct(0.98);
  }
  if (!(hi > lo)) {  // flat: centre the single height in the ramp
    lo -= 0.5;
    hi += 0.5;
  }
  return {lo, hi};
}

namespace {

ColourRange elevationRange(const float* v, std::size_t n) {
  ElevationSample s(n);
  s.add(0, v, n);
  if (s.needsEveryCell()) {
    s.countFinite(v, n);
    s.addEvery(v, n);
  }
  return s.range();
}

ColourRange pdmRange(const float* v, std::size_t n) {
  double mx = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(v[i])) mx = std::max(mx, double(v[i]));
  return {0, mx > 0 ? mx : 1};
}

}  // namespace

ColourRange colourRange(RenderLayer layer, const Raster<float>& values) {
  const std::size_t n = std::size_t(values.geometry.rows) * values.geometry.cols;
  if (layer == RenderLayer::Elevation) return elevationRange(values.values.data(), n);
  if (layer == RenderLayer::Pdm) return pdmRange(values.values.data(), n);
  return {};
}

RenderLayer renderLayerFromName(const std::string& name) {
  for (auto l : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope,
                 RenderLayer::Traversability, RenderLayer::Pdm})
    if (name == renderLayerName(l)) return l;
  throw Error(ErrorCode::NotFound, "layer",
              "unknown layer '" + name +
                  "'; valid layers: elevation, hillshade, slope, traversability, pdm");
}

const char* renderLayerName(RenderLayer layer) {
  switch (layer) {
    case RenderLayer::Elevation: return "elevation";
    case RenderLayer::Hillshade: return "hillshade";
    case RenderLayer::Slope: return "slope";
    case RenderLayer::Traversability: return "traversability";
    case RenderLayer::Pdm: return "pdm";
  }
  return "?";
}

Image renderLayer(RenderLayer layer, const RenderInput& input, const RenderOptions& options) {
  // 1. The display grid (and, for elevation, the shading grid at the same size).
  DisplayGrid grid, shade;
  const GridGeometry* geom = nullptr;
  int outRows = 0, outCols = 0;
  switch (layer) {
    case RenderLayer::Elevation: {
      const auto& z = required(layer, input.dem ? &input.dem->z : nullptr, "DEM");
      geom = &z.geometry;
      displaySize(geom->rows, geom->cols, options.maxSize, outRows, outCols);
      grid = downsampleMean(z, outRows, outCols);
      if (input.hillshade != nullptr) {  // optional: without it the tints are flat
        const auto& hs = *input.hillshade;
        if (hs.geometry.rows != geom->rows || hs.geometry.cols != geom->cols)
          throw Error(ErrorCode::InvalidInput, "hillshade",
                      "the hillshade raster does not match the DEM's size");
        shade = downsampleMean(hs, outRows, outCols);
      }
      break;
    }
    case RenderLayer::Hillshade:
    case RenderLayer::Slope:
    case RenderLayer::Pdm: {
      const Raster<float>* src = layer == RenderLayer::Hillshade ? input.hillshade
                                 : layer == RenderLayer::Slope   ? input.slopeDeg
                                                                 : input.pdm;
      const auto& r = required(layer, src,
                               layer == RenderLayer::Hillshade ? "hillshade raster"
                               : layer == RenderLayer::Slope   ? "slope raster"
                                                               : "PDM raster");
      geom = &r.geometry;
      displaySize(geom->rows, geom->cols, options.maxSize, outRows, outCols);
      grid = downsampleMean(r, outRows, outCols);
      break;
    }
    case RenderLayer::Traversability: {
      const auto& c = required(layer, input.classes, "traversability class raster");
      geom = &c.geometry;
      displaySize(geom->rows, geom->cols, options.maxSize, outRows, outCols);
      grid = downsampleWorstClass(c, outRows, outCols);
      break;
    }
  }

  // 2. Scale and legend. Statistics come from the displayed grid, so the picture always spans
  // its full colour range; the legend labels are in the source units.
  RampLegend scale;
  std::vector<ClassItem> classes;
  switch (layer) {
    case RenderLayer::Elevation: {
      const ColourRange cr = options.range ? *options.range : elevationRange(grid.data(), grid.size());
      const double lo = cr.lo, hi = cr.hi;
      // The ramp spans the 2nd to 98th percentile: the title says so, since the map's own
      // range (its info) is wider.
      scale = {"elevation (m), 2-98 %", lo, hi, {(lo + hi) / 2}, [](double v, const RampLegend& l) {
                return elevationTint(v, l.lo, l.hi - l.lo);
              }};
      break;
    }
    case RenderLayer::Hillshade:
      scale = {"hillshade", 1, 255, {}, [](double v, const RampLegend&) { return hillshadeGrey(v); }};
      break;
    case RenderLayer::Slope:
      scale = {"slope (deg)", 0, 45, {10, 15, 30},
              [](double v, const RampLegend&) { return slopeColour(v); }};
      break;
    case RenderLayer::Pdm: {
      const ColourRange cr = options.range ? *options.range : pdmRange(grid.data(), grid.size());
      scale = {"probability mass", 0, cr.hi, {}, [](double v, const RampLegend& l) { return massColour(v, l.hi); }};
      break;
    }
    case RenderLayer::Traversability:
      for (int c = 0; c < 4; ++c)
        classes.push_back(
            {kClassColours[c], terrain::terrainClassName(static_cast<terrain::TerrainClass>(c))});
      break;
  }

  // 3. The image: map at the top-left, legend strip below (drawn at 1/k of the width, then
  // enlarged k× so its labels stay legible on a big picture).
  const bool isClasses = layer == RenderLayer::Traversability;
  const int k = std::max(1, options.legendScale);
  const int width = options.legend ? std::max(outCols, kMinLegendWidth * k) : outCols;
  const int stripWidth = width / k;
  const int stripHeight = !options.legend ? 0
                          : isClasses     ? layoutClassLegend(stripWidth, classes, nullptr)
                                          : kRampLegendHeight;
  const int legendHeight = stripHeight * k;
  Image img;
  img.width = width;
  img.height = outRows + legendHeight;
  img.rgba.assign(std::size_t(img.width) * img.height * 4, 0);  // transparent

  // One loop per layer, the colour inlined (the ramps' arithmetic is the legend's, unchanged): a
  // switch and a call through scale.colour for every pixel were a fifth of a tile's rendering.
  auto paint = [&](auto&& colourOf) {
    for (int r = 0; r < outRows; ++r) {
      std::uint8_t* p = &img.rgba[std::size_t(r) * width * 4];
      const float* values = grid.data() + std::size_t(r) * outCols;
      for (int c = 0; c < outCols; ++c, p += 4) {
        const Rgba px = colourOf(values[c], r, c);
        p[0] = px.r;
        p[1] = px.g;
        p[2] = px.b;
        p[3] = px.a;
      }
    }
  };
  switch (layer) {
    case RenderLayer::Elevation: {
      const double lo = scale.lo, span = scale.hi - scale.lo;
      paint([&](float v, int r, int c) {
        if (!std::isfinite(v)) return kTransparent;
        const Rgba tint = elevationTint(v, lo, span);
        const float s = shade.empty() ? kNaN : shade.at(r, c);
        // Relief: tint × shade, softened so shadowed slopes keep some colour.
        const double f = std::isfinite(s) ? 0.3 + 0.7 * s / kNeutralShade : 1.0;
        return Rgba{toByte(tint.r * f), toByte(tint.g * f), toByte(tint.b * f), 255};
      });
      break;
    }
    case RenderLayer::Hillshade:
      paint([](float v, int, int) { return std::isfinite(v) ? hillshadeGrey(v) : kTransparent; });
      break;
    case RenderLayer::Slope:
      paint([](float v, int, int) { return std::isfinite(v) ? slopeColour(v) : kTransparent; });
      break;
    case RenderLayer::Pdm: {
      const double hi = scale.hi;
      paint([&](float v, int, int) {
        // Opacity grows with the mass (√ so the tails still show): a PDM is drawn over the
        // map, and an opaque ramp down to ~0 tinted the whole map one colour.
        if (!(std::isfinite(v) && v > 0)) return kTransparent;
        Rgba px = massColour(v, hi);
        px.a = toByte(255.0 * std::sqrt(std::min(1.0, v / hi)));
        return px;
      });
      break;
    }
    case RenderLayer::Traversability:
      paint([](float v, int, int) { return kClassColours[std::clamp(static_cast<int>(v), 0, 3)]; });
      break;
  }

  if (options.legend) {
    Image strip;
    strip.width = stripWidth;
    strip.height = stripHeight;
    strip.rgba.assign(std::size_t(strip.width) * strip.height * 4, 0);
    if (isClasses)
      drawClassLegend(strip, 0, stripHeight, "traversability", classes);
    else
      drawRampLegend(strip, 0, scale);
    for (int y = 0; y < legendHeight; ++y)
      for (int x = 0; x < width; ++x) {
        const int sx = std::min(x / k, strip.width - 1), sy = y / k;
        std::copy_n(&strip.rgba[(std::size_t(sy) * strip.width + sx) * 4], 4,
                    &img.rgba[(std::size_t(outRows + y) * width + x) * 4]);
      }
  }
  return img;
}

}  // namespace rover::maps
