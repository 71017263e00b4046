#include "maps/render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <bit>
#include <iterator>
#include <numbers>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/common/error.hpp"
#include "core/terrain/hillshade_light.hpp"
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
// An elevation pixel: the tint of height v shaded by s (hillshade 1..255, NaN: unshaded). Relief is
// tint × shade, softened so shadowed slopes keep some colour.
Rgba shadedTint(float v, float s, double lo, double span) {
  if (!std::isfinite(v)) return kTransparent;
  const Rgba tint = elevationTint(v, lo, span);
  const double f = std::isfinite(s) ? 0.3 + 0.7 * s / kNeutralShade : 1.0;
  return Rgba{toByte(tint.r * f), toByte(tint.g * f), toByte(tint.b * f), 255};
}
Rgba slopeColour(double degrees) { return rampColour(kSlope, degrees); }
Rgba massColour(double v, double hi) { return rampColour(kPerceptual, v / hi); }

// slopeColour(float(terrain::slopeDegrees(x, y))) of Horn's sums without the arctangent for all but
// a few cells in a hundred (issue 24: the arctangent was a sixth of a cold slope tile's CPU). The
// colour depends on the gradient's magnitude g = √(x² + y²) only, and g ≥ 1 (45°, where the ramp
// ends) is the last stop's. Below, a table of kBins bins of g: a bin holds its colour when the
// exact computation gives the same colour at both ends of the bin widened by kMargin and no stop of
// the ramp falls inside it. Then every g in the bin has that colour: between two stops each channel
// is a monotone function of the degrees (a ramp mixes linearly, then rounds), the degrees a
// monotone one of g up to the last bits of the arctangent, and the widening — a relative 1e-6 of g²,
// at least 3e-7 of the degrees — exceeds both those bits and the rounding of the degrees to float
// (6e-8), as it does the error of g² computed by multiplying by 1/(8·res)² instead of dividing.
// Other bins (each channel's change points, ~660 over 0..45°: about 1 % of the bins) take the exact
// path, as do NaN and the first millionth above g = 1. Pixels are byte for byte those of
// renderLayer over slopeHorn (test_maps checks the two on every cell of sweeps and tiles).
class SlopeTable {
 public:
  SlopeTable() {
    const std::size_t n = std::size(kSlope);
    for (int k = 0; k < kBins; ++k) {
      const double lo = double(k) / kBins, hi = double(k + 1) / kBins;
      const double g2lo = lo * lo * (1 - kMargin), g2hi = hi * hi * (1 + kMargin);
      const Rgba a = exact(g2lo), b = exact(g2hi);
      bool same = a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a;
      for (std::size_t i = 1; i < n; ++i) {  // stop 0 is the lowest slope: no ramp below it
        const double t = std::tan(kSlope[i].at * std::numbers::pi / 180);
        if (t * t >= g2lo && t * t <= g2hi) same = false;
      }
      bins_[k] = same ? a : kTransparent;  // alpha 0: look closer (every slope colour is opaque)
    }
    last_ = exact(2.0);
  }

  // Horn's sums (sx, sy); ex = 8·dx(r), ny = 8·nsres as slopeHorn divides by them; kx = 1/ex²,
  // ky = 1/ny²; g2 = squared(sx, sy, kx, ky) and root = √g2, computed by the caller (renderSlope:
  // a row at a time, vectorised).
  static double squared(float sx, float sy, double kx, double ky) { return double(sx) * sx * kx + double(sy) * sy * ky; }
  Rgba colour(float sx, float sy, double g2, double root, double ex, double ny) const {
    if (g2 < 1.0) {
      const Rgba c = bins_[std::min(static_cast<int>(root * kBins), kBins - 1)];
      if (c.a != 0) return c;
    } else if (g2 >= 1.0 + kMargin) {  // also +inf: 90°
      return last_;
    }
    const float v = static_cast<float>(terrain::slopeDegrees(sx / ex, sy / ny));  // NaN: gradients of ±inf
    return std::isfinite(v) ? slopeColour(v) : kTransparent;
  }

 private:
  static constexpr int kBins = 1 << 16;
  static constexpr double kMargin = 1e-6;
  static Rgba exact(double g2) {
    return slopeColour(static_cast<float>(std::atan(std::sqrt(g2)) * (180.0 / std::numbers::pi)));
  }
  std::array<Rgba, kBins> bins_;
  Rgba last_;
};

}  // namespace

Image renderSlope(const terrain::Dem& dem) {
  const auto& z = required(RenderLayer::Slope, &dem.z, "DEM");
  static const SlopeTable table;  // 256 KiB, built once (~130 000 arctangents)
  const int rows = z.geometry.rows, cols = z.geometry.cols;
  Image img;
  img.width = cols;
  img.height = rows;
  img.rgba.assign(std::size_t(rows) * cols * 4, 0);  // transparent: borders, nodata windows
  // This row's Horn sums and whether the 3 × 3 window has data, computed in a loop the compiler
  // vectorises (terrain::hornRow's arithmetic, in its order); the colours then come from the table.
  std::vector<float> sxs(cols), sys(cols);
  std::vector<double> window(cols);  // the 3 × 3 window's sum: NaN where it has no data
  std::vector<double> g2s(cols), roots(cols);  // the squared gradient (in tan² of the slope), its root
  for (int r = 1; r < rows - 1; ++r) {
    const double ex = 8.0 * dem.dx(r), ny = 8.0 * -dem.dy();
    const double kx = 1 / (ex * ex), ky = 1 / (ny * ny);
    const float* up = &z(r - 1, 0);
    const float* row = &z(r, 0);
    const float* down = &z(r + 1, 0);
    for (int c = 1; c < cols - 1; ++c) {
      const float a = up[c - 1], b = up[c], cc = up[c + 1], d = row[c - 1], e = row[c + 1], g = down[c - 1],
                  h = down[c], i = down[c + 1];
      window[c] = double(a) + b + cc + d + e + g + h + i + row[c];
      const float sx = (a + d + d + g) - (cc + e + e + i), sy = (g + h + h + i) - (a + b + b + cc);
      sxs[c] = sx;
      sys[c] = sy;
      g2s[c] = SlopeTable::squared(sx, sy, kx, ky);
      roots[c] = std::sqrt(g2s[c]);
    }
    std::uint8_t* out = &img.rgba[std::size_t(r) * cols * 4];
    for (int c = 1; c < cols - 1; ++c) {
      if (std::isnan(window[c])) continue;
      const Rgba px = table.colour(sxs[c], sys[c], g2s[c], roots[c], ex, ny);
      std::uint8_t* p = out + std::size_t(c) * 4;
      p[0] = px.r;
      p[1] = px.g;
      p[2] = px.b;
      p[3] = px.a;
    }
  }
  return img;
}

namespace {

// The hypsometric ramp's stops are a quarter apart, so rampColour(kHypsometric, u)'s search for the
// segment is i = 1 + [u > ¼] + [u > ½] + [u > ¾] for u > 0, and its division by the segment's
// width 0.25 is an exact multiplication by 4. What is left is the same arithmetic without a
// branch or a table look-up a pixel.
static_assert(std::size(kHypsometric) == 5);
constexpr bool quarterStops() {
  for (std::size_t i = 0; i < std::size(kHypsometric); ++i)
    if (kHypsometric[i].at != 0.25 * double(i)) return false;
  return true;
}
static_assert(quarterStops(), "hypsometricTint assumes stops at 0, 0.25, 0.5, 0.75, 1");

// rampColour(kHypsometric, u)'s channels, bit for bit (render tests compare the two).
struct TintChannels {
  int r, g, b;
};
inline TintChannels hypsometricTint(double u) {
  // else (also NaN) the first stop's colour: segment 1 at t = 0
  const double above = u > 0, past1 = u > 0.25, past2 = u > 0.5, past3 = u > 0.75;
  // Stop i − 1 (x) and stop i (y) of a channel as sums of the steps passed: small integers, so exact.
  auto pick = [&](double s0, double s1, double s2, double s3) {
    return s0 + past1 * (s1 - s0) + past2 * (s2 - s1) + past3 * (s3 - s2);
  };
  constexpr const Stop* k = kHypsometric;
  const double at = pick(k[0].at, k[1].at, k[2].at, k[3].at);  // quarters: exact
  // A NaN u (nodata, or a zero span) gives 0: std::max(a, b) is a unless a < b, so 0 comes first
  // (max(NaN, 0) would be NaN, and casting it to int in mix undefined).
  const double t = above * std::min(1.0, std::max(0.0, (u - at) * 4.0));
  auto mix = [&](double a0, double a1, double a2, double a3, double a4) {
    const double x = pick(a0, a1, a2, a3), y = pick(a1, a2, a3, a4);
    return static_cast<int>(x + (y - x) * t + 0.5);  // in [0, 255.5]: truncation as rampColour's
  };
  return {mix(k[0].r, k[1].r, k[2].r, k[3].r, k[4].r), mix(k[0].g, k[1].g, k[2].g, k[3].g, k[4].g),
          mix(k[0].b, k[1].b, k[2].b, k[3].b, k[4].b)};
}

}  // namespace

namespace {

// Row r's hillshade as terrain::hillshade gives it (the default sun): shade[c] for the interior
// columns, NaN where the 3 × 3 window has no data; the first and last column are NaN. One plain
// loop the compiler vectorises (issue 24: the per-pixel call chain — hornRow's callback,
// HillshadeLight, the ramp's search — was over half of a cold elevation tile's CPU), with the IEEE
// operations of hornRow and hillshade() in their order: no reassociation, no reciprocals, so the
// floats are the old ones (render.cpp is built with -fno-math-errno so std::sqrt needs no errno
// branch, -fno-trapping-math so the select below needs no branch).
void shadeRow(const terrain::Dem& dem, int r, float* shade) {
  static const terrain::HillshadeLight light;  // terrain::hillshade's default sun
  const auto& z = dem.z;
  const int cols = z.geometry.cols;
  const double ex = 8.0 * dem.dx(r), ny = 8.0 * -dem.dy();
  const float* up = &z(r - 1, 0);
  const float* row = &z(r, 0);
  const float* down = &z(r + 1, 0);
  shade[0] = shade[cols - 1] = kNaN;
  for (int c = 1; c < cols - 1; ++c) {
    const float a = up[c - 1], b = up[c], cc = up[c + 1], d = row[c - 1], e = row[c + 1], g = down[c - 1],
                h = down[c], i = down[c + 1];
    const bool noData = std::isnan(double(a) + b + cc + d + e + g + h + i + row[c]);
    const float sx = (a + d + d + g) - (cc + e + e + i), sy = (g + h + h + i) - (a + b + b + cc);
    const float s = static_cast<float>(light(sx / ex, sy / ny));
    shade[c] = noData ? kNaN : s;
  }
}

}  // namespace

// Per row: the shade (shadeRow), the shading factor, then tint × factor rounded as toByte; each a
// loop over arrays that the compiler vectorises.
Image renderShadedElevation(const terrain::Dem& dem, const ColourRange& range) {
  static_assert(std::endian::native == std::endian::little, "pixels are packed R, G, B, A from the low byte");
  const auto& z = required(RenderLayer::Elevation, &dem.z, "DEM");
  const int rows = z.geometry.rows, cols = z.geometry.cols;
  const double lo = range.lo, span = range.hi - range.lo;
  Image img;
  img.width = cols;
  img.height = rows;
  img.rgba.assign(std::size_t(rows) * cols * 4, 0);
  std::vector<float> shade(cols, kNaN);  // NaN on the first and last row
  // This row's shading factor (shadedTint's f): 1 where the shade is NaN (an unshaded tint).
  std::vector<double> factor(cols);
  std::vector<std::uint32_t> rowPixels(cols);  // this row's RGBA, little-endian
  for (int r = 0; r < rows; ++r) {
    if (r > 0 && r < rows - 1) shadeRow(dem, r, shade.data());
    else std::fill(shade.begin(), shade.end(), kNaN);
    // The cell's scale (a product, not a select, so the loop vectorises): the factor, or 0 for a
    // cell without a height (then every channel is 0 × … = 0: transparent black).
    const float* v = &z(r, 0);
    double* f = factor.data();
    for (int c = 0; c < cols; ++c) {
      const float s = shade[c];
      const double shaded = 0.3 + 0.7 * double(s) / kNeutralShade;
      f[c] = (std::isfinite(s) ? shaded : 1.0) * double(std::fabs(v[c]) <= std::numeric_limits<float>::max());
    }
    std::uint32_t* p = rowPixels.data();
    for (int c = 0; c < cols; ++c) {
      const TintChannels t = hypsometricTint((double(v[c]) - lo) / span);
      // toByte(tint × f): the product is ≥ 0 (tints and factors are), so min(·, 255) + ½ truncated.
      const double k = f[c];
      auto byte = [k](int x) { return static_cast<std::uint32_t>(std::min(x * k, 255.0) + 0.5); };
      p[c] = byte(t.r) | byte(t.g) << 8 | byte(t.b) << 16 | (k > 0 ? 0xff000000u : 0u);  // R, G, B, A in memory
    }
    std::memcpy(&img.rgba[std::size_t(r) * cols * 4], p, std::size_t(cols) * 4);
  }
  return img;
}

Image renderHillshade(const terrain::Dem& dem) {
  const auto& z = required(RenderLayer::Hillshade, &dem.z, "DEM");
  const int rows = z.geometry.rows, cols = z.geometry.cols;
  Image img;
  img.width = cols;
  img.height = rows;
  img.rgba.assign(std::size_t(rows) * cols * 4, 0);  // transparent: borders, nodata windows
  std::vector<float> shade(cols);
  std::vector<std::uint32_t> rowPixels(cols);  // this row's RGBA, little-endian
  for (int r = 1; r < rows - 1; ++r) {
    shadeRow(dem, r, shade.data());
    for (int c = 0; c < cols; ++c) {  // hillshadeGrey: toByte of a shade in 1..255, grey, opaque
      const float s = shade[c];
      // min(255, NaN) is 255 (NaN in the first and last columns): the cast stays defined.
      const auto g = static_cast<std::uint32_t>(std::min(255.0, double(s)) + 0.5);
      rowPixels[c] = std::isfinite(s) ? g | g << 8 | g << 16 | 0xff000000u : 0u;
    }
    std::memcpy(&img.rgba[std::size_t(r) * cols * 4], rowPixels.data(), std::size_t(cols) * 4);
  }
  return img;
}

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
      paint([&](float v, int r, int c) { return shadedTint(v, shade.empty() ? kNaN : shade.at(r, c), lo, span); });
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
