#include <cpl_vsi.h>
#include <doctest/doctest.h>
#include <gdal.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/gdal_env.hpp"
#include "maps/layer_overview.hpp"
#include "maps/render.hpp"

using rover::Error;
using rover::ErrorCode;
using rover::GridGeometry;
using rover::Raster;
using namespace rover::maps;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Raster<float> floatRaster(int rows, int cols, float fill) {
  return Raster<float>(GridGeometry{rows, cols, 1.0, 1.0}, fill);
}

struct Px {
  int r, g, b, a;
};

Px pixel(const Image& img, int x, int y) {
  const auto* p = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
  return {p[0], p[1], p[2], p[3]};
}

bool samePx(Px a, Px b) { return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a; }

double luminance(Px p) { return 0.2126 * p.r + 0.7152 * p.g + 0.0722 * p.b; }

RenderOptions noLegend(int maxSize = 0) {
  RenderOptions o;
  o.legend = false;
  o.maxSize = maxSize;
  return o;
}

// Decodes PNG bytes with GDAL (through /vsimem/) into an RGBA image; bands reports the band count.
Image decodePng(const std::vector<std::uint8_t>& bytes, int& bands) {
  ensureGdal();
  static int counter = 0;
  const std::string path = "/vsimem/test_render_decode_" + std::to_string(counter++) + ".png";
  VSILFILE* f = VSIFileFromMemBuffer(path.c_str(), const_cast<GByte*>(bytes.data()),
                                     static_cast<vsi_l_offset>(bytes.size()), FALSE);
  REQUIRE(f != nullptr);
  VSIFCloseL(f);
  GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr,
                               nullptr, nullptr);
  REQUIRE(ds != nullptr);
  Image img;
  img.width = GDALGetRasterXSize(ds);
  img.height = GDALGetRasterYSize(ds);
  bands = GDALGetRasterCount(ds);
  if (bands == 4) {
    img.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
    CHECK(GDALDatasetRasterIO(ds, GF_Read, 0, 0, img.width, img.height, img.rgba.data(),
                              img.width, img.height, GDT_Byte, 4, nullptr, 4, 4 * img.width,
                              1) == CE_None);
  }
  GDALClose(ds);
  VSIUnlink(path.c_str());
  return img;
}

template <class F>
void checkError(F&& f, ErrorCode code, const std::string& field, const std::string& inMessage) {
  try {
    f();
    FAIL("no rover::Error thrown");
  } catch (const Error& e) {
    CHECK(e.code() == code);
    CHECK(e.field() == field);
    CHECK_MESSAGE(std::string(e.what()).find(inMessage) != std::string::npos, e.what());
  }
}

}  // namespace

TEST_CASE("render: layer names round-trip, unknown names are NotFound listing the valid ones") {
  for (auto l : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope,
                 RenderLayer::Traversability, RenderLayer::Pdm})
    CHECK(renderLayerFromName(renderLayerName(l)) == l);
  CHECK(renderLayerFromName("traversability") == RenderLayer::Traversability);
  for (const char* bad : {"", "Slope", "aspect", "slope "}) {
    checkError([&] { renderLayerFromName(bad); }, ErrorCode::NotFound, "layer",
               "elevation, hillshade, slope, traversability, pdm");
  }
}

TEST_CASE("render: a missing or empty input raster is InvalidInput on field layer") {
  const RenderInput none;
  for (auto l : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope,
                 RenderLayer::Traversability, RenderLayer::Pdm})
    checkError([&] { renderLayer(l, none); }, ErrorCode::InvalidInput, "layer",
               renderLayerName(l));

  // Inputs for other layers do not help.
  const auto slope = floatRaster(4, 4, 5.0f);
  RenderInput onlySlope;
  onlySlope.slopeDeg = &slope;
  checkError([&] { renderLayer(RenderLayer::Pdm, onlySlope); }, ErrorCode::InvalidInput, "layer",
             "PDM");

  const Raster<float> empty;
  RenderInput emptySlope;
  emptySlope.slopeDeg = &empty;
  checkError([&] { renderLayer(RenderLayer::Slope, emptySlope); }, ErrorCode::InvalidInput,
             "layer", "empty slope raster");

  // A shading raster of another size than the DEM.
  rover::terrain::Dem dem;
  dem.z = floatRaster(4, 4, 10.0f);
  const auto shade = floatRaster(3, 4, 180.0f);
  RenderInput in;
  in.dem = &dem;
  in.hillshade = &shade;
  checkError([&] { renderLayer(RenderLayer::Elevation, in); }, ErrorCode::InvalidInput,
             "hillshade", "size");
}

TEST_CASE("render: PNG bytes carry the signature and decode with GDAL to the same RGBA") {
  // 20 rows × 30 cols; width is the column count.
  auto slope = floatRaster(20, 30, 0.0f);
  for (int r = 0; r < 20; ++r)
    for (int c = 0; c < 30; ++c) slope(r, c) = static_cast<float>(c * 1.5);
  slope(3, 4) = kNaN;
  RenderInput in;
  in.slopeDeg = &slope;

  for (bool legend : {false, true}) {
    RenderOptions o;
    o.legend = legend;
    const Image img = renderLayer(RenderLayer::Slope, in, o);
    const auto png = encodePng(img);
    REQUIRE(png.size() > 8);
    const std::uint8_t sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    for (int i = 0; i < 8; ++i) CHECK(png[i] == sig[i]);
    int bands = 0;
    const Image back = decodePng(png, bands);
    CHECK(bands == 4);
    CHECK(back.width == img.width);
    CHECK(back.height == img.height);
    CHECK(back.rgba == img.rgba);  // lossless
    if (!legend) {
      CHECK(img.width == 30);
      CHECK(img.height == 20);
    }
  }

  Image bad;
  bad.width = 3;
  bad.height = 2;
  bad.rgba.resize(5);
  checkError([&] { encodePng(bad); }, ErrorCode::InvalidInput, "image", "RGBA");
}

TEST_CASE("render: the legend adds a strip below the map, widened for narrow maps") {
  const auto slope = floatRaster(100, 200, 12.0f);
  RenderInput in;
  in.slopeDeg = &slope;
  const Image plain = renderLayer(RenderLayer::Slope, in, noLegend());
  const Image withLegend = renderLayer(RenderLayer::Slope, in);
  CHECK(plain.width == 200);
  CHECK(plain.height == 100);
  CHECK(withLegend.width == 200);
  CHECK(withLegend.height >= 100 + 28);
  // The map itself is unchanged, the strip is opaque, and it holds dark text pixels.
  CHECK(samePx(pixel(withLegend, 50, 50), pixel(plain, 50, 50)));
  int ink = 0, notOpaque = 0;
  for (int y = 100; y < withLegend.height; ++y)
    for (int x = 0; x < withLegend.width; ++x) {
      const Px p = pixel(withLegend, x, y);
      if (p.a != 255) ++notOpaque;
      if (p.r < 60 && p.g < 60 && p.b < 60) ++ink;
    }
  CHECK(notOpaque == 0);
  CHECK(ink > 50);
  // The colour bar runs from the 0° colour (green) at its left to 45° (dark red) at its right.
  const int barY = 100 + 15;
  const Px left = pixel(withLegend, 3, barY), right = pixel(withLegend, 196, barY);
  CHECK(left.g > left.r);
  CHECK(right.r > 3 * right.g);

  // A narrow map: the strip is wider than the map, the area right of the map transparent.
  const auto narrowSlope = floatRaster(30, 40, 5.0f);
  RenderInput narrowIn;
  narrowIn.slopeDeg = &narrowSlope;
  const Image narrow = renderLayer(RenderLayer::Slope, narrowIn);
  CHECK(narrow.width >= 150);
  CHECK(narrow.width > 40);
  CHECK(narrow.height >= 30 + 28);
  CHECK(pixel(narrow, 20, 10).a == 255);
  CHECK(pixel(narrow, 100, 10).a == 0);
  CHECK(pixel(narrow, 100, 30 + 2).a == 255);

  // Every layer has a legend.
  rover::terrain::Dem dem;
  dem.z = floatRaster(10, 10, 3.0f);
  Raster<std::uint8_t> classes(GridGeometry{10, 10, 1, 1}, 0);
  const auto pdm = floatRaster(10, 10, 0.01f);
  const auto shade = floatRaster(10, 10, 200.0f);
  RenderInput all;
  all.dem = &dem;
  all.hillshade = &shade;
  all.classes = &classes;
  all.pdm = &pdm;
  for (auto l : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Traversability,
                 RenderLayer::Pdm}) {
    const Image img = renderLayer(l, all);
    CHECK(img.height >= 10 + 28);
    CHECK(img.width >= 150);
  }
}

TEST_CASE("render: maxSize box-averages down to the limit and keeps the aspect ratio") {
  auto wide = floatRaster(200, 400, 0.0f);
  RenderInput in;
  in.slopeDeg = &wide;
  Image img = renderLayer(RenderLayer::Slope, in, noLegend(100));
  CHECK(img.width == 100);
  CHECK(img.height == 50);

  auto tall = floatRaster(400, 200, 0.0f);
  in.slopeDeg = &tall;
  img = renderLayer(RenderLayer::Slope, in, noLegend(100));
  CHECK(img.width == 50);
  CHECK(img.height == 100);

  img = renderLayer(RenderLayer::Slope, in, noLegend(1000));  // already small enough
  CHECK(img.width == 200);
  CHECK(img.height == 400);

  auto sliver = floatRaster(3, 1000, 0.0f);
  in.slopeDeg = &sliver;
  img = renderLayer(RenderLayer::Slope, in, noLegend(100));
  CHECK(img.width == 100);
  CHECK(img.height == 1);

  // 4×4 -> 2×2: each output pixel is the mean of its 2×2 block, NaN ignored.
  // block (0,0): 0, 20, 20, 40 -> 20      block (0,1): 30, NaN, NaN, NaN -> 30
  // block (1,0): NaN everywhere -> nodata block (1,1): 44 everywhere -> 44
  auto src = floatRaster(4, 4, kNaN);
  src(0, 0) = 0;
  src(0, 1) = 20;
  src(1, 0) = 20;
  src(1, 1) = 40;
  src(0, 2) = 30;
  src(2, 2) = src(2, 3) = src(3, 2) = src(3, 3) = 44;
  in.slopeDeg = &src;
  img = renderLayer(RenderLayer::Slope, in, noLegend(2));
  REQUIRE(img.width == 2);
  REQUIRE(img.height == 2);
  auto uniform = [&](float v) {
    const auto one = floatRaster(1, 1, v);
    RenderInput i1;
    i1.slopeDeg = &one;
    return pixel(renderLayer(RenderLayer::Slope, i1, noLegend()), 0, 0);
  };
  CHECK(samePx(pixel(img, 0, 0), uniform(20)));
  CHECK(samePx(pixel(img, 1, 0), uniform(30)));
  CHECK(pixel(img, 0, 1).a == 0);
  CHECK(samePx(pixel(img, 1, 1), uniform(44)));
}

TEST_CASE("render: nodata cells are transparent, data cells opaque") {
  auto v = floatRaster(3, 3, 7.0f);
  v(1, 2) = kNaN;
  rover::terrain::Dem dem;
  dem.z = v;
  auto shade = floatRaster(3, 3, kNaN);  // a 3×3 hillshade is all border: NaN
  RenderInput in;
  in.dem = &dem;
  in.hillshade = &v;
  in.slopeDeg = &v;
  in.pdm = &v;
  for (auto l : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope,
                 RenderLayer::Pdm}) {
    const Image img = renderLayer(l, in, noLegend());
    CAPTURE(renderLayerName(l));
    CHECK(pixel(img, 2, 1).a == 0);
    CHECK(pixel(img, 0, 0).a == 255);
    CHECK(pixel(img, 1, 2).a == 255);
  }
  // NaN shading (the hillshade's border) is neutral: not black, same as no shading at all.
  in.hillshade = &shade;
  const Image shaded = renderLayer(RenderLayer::Elevation, in, noLegend());
  in.hillshade = nullptr;
  const Image unshaded = renderLayer(RenderLayer::Elevation, in, noLegend());
  CHECK(samePx(pixel(shaded, 0, 0), pixel(unshaded, 0, 0)));
  CHECK(luminance(pixel(shaded, 0, 0)) > 60);
}

TEST_CASE("render: traversability classes get their colours, overviews keep the worst class") {
  using rover::terrain::TerrainClass;
  // 4×4 classes:     0 0 | 1 3
  //                  0 0 | 3 3
  //                  ----+----
  //                  3 3 | 0 2
  //                  3 3 | 0 0
  Raster<std::uint8_t> cls(GridGeometry{4, 4, 1, 1}, 0);
  cls(0, 2) = 1;
  cls(0, 3) = cls(1, 2) = cls(1, 3) = 3;
  cls(2, 0) = cls(2, 1) = cls(3, 0) = cls(3, 1) = 3;
  cls(2, 3) = 2;
  RenderInput in;
  in.classes = &cls;
  const Image full = renderLayer(RenderLayer::Traversability, in, noLegend());
  const Px trav = pixel(full, 0, 0), risk = pixel(full, 2, 0), imp = pixel(full, 3, 2),
           nodata = pixel(full, 3, 0);
  // traversable green, high-risk amber, impassable red, nodata dark grey and half transparent.
  CHECK((trav.g > 140 && trav.g > trav.r + 60 && trav.g > trav.b + 60 && trav.a == 255));
  CHECK((risk.r > 200 && risk.g > 120 && risk.g < 200 && risk.b < 60 && risk.a == 255));
  CHECK((imp.r > 180 && imp.g < 80 && imp.b < 80 && imp.a == 255));
  CHECK((nodata.r < 80 && nodata.g < 80 && nodata.b < 80 && nodata.a > 0 && nodata.a < 255));

  const Image over = renderLayer(RenderLayer::Traversability, in, noLegend(2));
  REQUIRE(over.width == 2);
  CHECK(samePx(pixel(over, 0, 0), trav));    // all traversable
  CHECK(samePx(pixel(over, 1, 0), risk));    // high risk beats nodata
  CHECK(samePx(pixel(over, 0, 1), nodata));  // nodata only when all are
  CHECK(samePx(pixel(over, 1, 1), imp));     // the worst class wins

  // The legend lists the four classes with swatches: their colours appear in the strip.
  const Image withLegend = renderLayer(RenderLayer::Traversability, in);
  CHECK(withLegend.height >= 4 + 28);
  bool seen[3] = {false, false, false};
  for (int y = 4; y < withLegend.height; ++y)
    for (int x = 0; x < withLegend.width; ++x) {
      const Px p = pixel(withLegend, x, y);
      seen[0] = seen[0] || samePx(p, trav);
      seen[1] = seen[1] || samePx(p, risk);
      seen[2] = seen[2] || samePx(p, imp);
    }
  CHECK((seen[0] && seen[1] && seen[2]));
}

TEST_CASE("render: the slope ramp grows redder with slope, thresholds included") {
  const std::vector<float> slopes = {0, 5, 9.9f, 10, 12, 15, 20, 30, 40, 45};
  auto row = floatRaster(1, static_cast<int>(slopes.size()), 0.0f);
  for (std::size_t i = 0; i < slopes.size(); ++i) row(0, static_cast<int>(i)) = slopes[i];
  RenderInput in;
  in.slopeDeg = &row;
  const Image img = renderLayer(RenderLayer::Slope, in, noLegend());
  double previous = 1e9;
  for (int i = 0; i < img.width; ++i) {
    const Px p = pixel(img, i, 0);
    const double greenPerRed = (p.g + 1.0) / (p.r + 1.0);
    CAPTURE(slopes[i]);
    CHECK(greenPerRed < previous);
    previous = greenPerRed;
  }
  CHECK(pixel(img, 0, 0).g > pixel(img, 0, 0).r);  // 0°: green
  // Beyond 45° the ramp saturates.
  auto steep = floatRaster(1, 2, 45.0f);
  steep(0, 1) = 80.0f;
  in.slopeDeg = &steep;
  const Image sat = renderLayer(RenderLayer::Slope, in, noLegend());
  CHECK(samePx(pixel(sat, 0, 0), pixel(sat, 1, 0)));
}

TEST_CASE("render: elevation spans the 2-98 percentile heights and is shaded by the hillshade") {
  // 10×10 heights 0..99 plus one spike: the spike is clipped instead of flattening the ramp.
  rover::terrain::Dem dem;
  dem.z = floatRaster(10, 10, 0.0f);
  for (int i = 0; i < 100; ++i) dem.z.at(i) = static_cast<float>(i);
  dem.z(9, 9) = 1e6f;
  RenderInput in;
  in.dem = &dem;
  const Image img = renderLayer(RenderLayer::Elevation, in, noLegend());
  const Px low = pixel(img, 0, 0), mid = pixel(img, 0, 5), high = pixel(img, 8, 9);
  CHECK(std::abs(luminance(high) - luminance(low)) > 60);
  CHECK(!samePx(mid, low));
  CHECK(!samePx(mid, high));
  CHECK(samePx(pixel(img, 9, 9), pixel(img, 8, 9)));  // both at or above the 98th percentile

  // Shading: a bright hillshade lightens, a dark one darkens.
  auto shade = floatRaster(10, 10, 180.3f);
  shade(5, 5) = 250.0f;
  shade(5, 6) = 30.0f;
  dem.z.values.setConstant(50.0f);
  dem.z(5, 5) = dem.z(5, 6) = 50.0f;
  in.hillshade = &shade;
  const Image lit = renderLayer(RenderLayer::Elevation, in, noLegend());
  const double flat = luminance(pixel(lit, 0, 0));
  CHECK(luminance(pixel(lit, 5, 5)) > flat + 10);
  CHECK(luminance(pixel(lit, 6, 5)) < flat - 30);

  // Hillshade layer: grey levels.
  in.hillshade = &shade;
  const Image hs = renderLayer(RenderLayer::Hillshade, in, noLegend());
  const Px g = pixel(hs, 5, 5);
  CHECK((g.r == 250 && g.g == 250 && g.b == 250 && g.a == 255));
}

// No ';' in the name: CTest's doctest discovery splits names there and then runs nothing.
TEST_CASE("render: the PDM ramp brightens with mass, zero mass is transparent, opacity grows") {
  auto pdm = floatRaster(1, 6, 0.0f);
  const float values[6] = {0.0f, 1e-6f, 2e-4f, 4e-4f, 7e-4f, 1e-3f};
  for (int i = 0; i < 6; ++i) pdm(0, i) = values[i];
  RenderInput in;
  in.pdm = &pdm;
  const Image img = renderLayer(RenderLayer::Pdm, in, noLegend());
  const Px zero = pixel(img, 0, 0);
  CHECK(zero.a == 0);  // drawn over the map: zero mass must not tint it (render.cpp)
  for (int i = 2; i < 6; ++i) {
    CHECK(luminance(pixel(img, i, 0)) > luminance(pixel(img, i - 1, 0)));
    CHECK(pixel(img, i, 0).a > pixel(img, i - 1, 0).a);
  }
  const Px top = pixel(img, 5, 0);
  CHECK((top.r > 200 && top.g > 200 && top.b < 100));  // the bright (yellow) end at the maximum
}

TEST_CASE("render: a 4096² slope raster gives a 1024 px overview with maxSize 1024") {
  auto slope = floatRaster(4096, 4096, 0.0f);
  for (int i = 0; i < slope.geometry.cellCount(); ++i)
    slope.at(i) = static_cast<float>((static_cast<std::int64_t>(i) * 7919) % 4500) / 100.0f;
  RenderInput in;
  in.slopeDeg = &slope;
  RenderOptions o;
  o.maxSize = 1024;
  const Image img = renderLayer(RenderLayer::Slope, in, o);
  CHECK(img.width == 1024);
  CHECK(img.height >= 1024 + 28);
  CHECK_FALSE(encodePng(img).empty());
}

TEST_CASE("render: an elevation ramp seen in pieces equals the whole grid's, also when the fixed stride meets only nodata") {
  // 3 M cells: the fixed stride is 3, and every third cell is nodata, so the sample falls back to
  // the finite cells, itself a stride through them (never a full-size copy of the grid).
  const std::size_t n = 3u << 20;
  std::vector<float> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = i % 3 == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(i);
  const GridGeometry g{3 << 10, 1 << 10, 1.0, 1.0};
  Raster<float> grid(g, 0.0f);
  std::copy(v.begin(), v.end(), grid.values.data());
  const ColourRange whole = colourRange(RenderLayer::Elevation, grid);
  ElevationSample s(n);
  const std::size_t piece = 1000 * 1024;  // pieces of whole rows, as an import streams them
  for (std::size_t first = 0; first < n; first += piece) s.add(first, v.data() + first, std::min(piece, n - first));
  REQUIRE(s.needsEveryCell());
  for (const bool counting : {true, false})
    for (std::size_t first = 0; first < n; first += piece) {
      const std::size_t k = std::min(piece, n - first);
      if (counting)
        s.countFinite(v.data() + first, k);
      else
        s.addEvery(v.data() + first, k);
    }
  const ColourRange streamed = s.range();
  CHECK(streamed.lo == whole.lo);
  CHECK(streamed.hi == whole.hi);
  // The 2nd and 98th percentiles of the finite heights, spread evenly over 0 … n, to within the
  // sampling.
  CHECK(whole.lo == doctest::Approx(0.02 * n).epsilon(0.01));
  CHECK(whole.hi == doctest::Approx(0.98 * n).epsilon(0.01));
}

TEST_CASE("render: renderSlope, renderShadedElevation and renderHillshade draw renderLayer's pixels over slopeHorn and hillshade") {
  // Slopes swept from 0° to ~60° along each row (a quadratic surface), tilted differently in each
  // row, with noise, so every colour of the ramps and thousands of cells next to a change of
  // colour are met; per-row cell widths (a geographic map); nodata, infinite and huge heights.
  const int rows = 240, cols = 1400;
  rover::terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{rows, cols, 1.0, 0.75}, 0.0f);
  std::uint32_t seed = 7;
  auto noise = [&] {
    seed = seed * 1664525u + 1013904223u;
    return double(seed >> 8) / double(1u << 24) - 0.5;
  };
  for (int r = 0; r < rows; ++r) {
    dem.rowCellWidth.push_back(1.0 + 0.002 * r);
    for (int c = 0; c < cols; ++c)
      dem.z(r, c) = static_cast<float>(0.0006 * c * c + 0.0004 * r * c + 0.02 * noise());
  }
  for (int k = 0; k < 60; ++k) dem.z(1 + (k * 37) % (rows - 2), 1 + (k * 91) % (cols - 2)) = kNaN;
  dem.z(5, 5) = std::numeric_limits<float>::infinity();
  dem.z(9, 9) = -std::numeric_limits<float>::infinity();
  for (int c = 20; c < 40; c += 2) dem.z(12, c) = 3e38f;  // gradients of ±inf
  const Raster<float> slope = rover::terrain::slopeHorn(dem);
  const Raster<float> shade = rover::terrain::hillshade(dem);
  RenderInput in;
  in.slopeDeg = &slope;
  const Image bySlope = renderLayer(RenderLayer::Slope, in, noLegend());
  const Image fused = renderSlope(dem);
  REQUIRE(fused.width == bySlope.width);
  REQUIRE(fused.height == bySlope.height);
  int different = 0, steep = 0;
  for (std::size_t i = 0; i < fused.rgba.size(); ++i) different += fused.rgba[i] != bySlope.rgba[i];
  for (int k = 0; k < rows * cols; ++k) steep += slope.at(k) > 45;
  CHECK(different == 0);
  CHECK(steep > 10000);  // the sweep went past the ramp's end
  const ColourRange range{50, 900};
  RenderOptions options = noLegend();
  options.range = &range;
  in = {};
  in.dem = &dem;
  in.hillshade = &shade;
  const Image byShade = renderLayer(RenderLayer::Elevation, in, options);
  const Image shaded = renderShadedElevation(dem, range);
  REQUIRE(shaded.rgba.size() == byShade.rgba.size());
  different = 0;
  for (std::size_t i = 0; i < shaded.rgba.size(); ++i) different += shaded.rgba[i] != byShade.rgba[i];
  CHECK(different == 0);
  const Image greys = renderLayer(RenderLayer::Hillshade, in, noLegend());
  const Image fusedGreys = renderHillshade(dem);
  REQUIRE(fusedGreys.rgba.size() == greys.rgba.size());
  CHECK(fusedGreys.rgba == greys.rgba);
}

TEST_CASE("render: the vectorised elevation and hillshade give renderLayer's bytes on the ramp's stops and at the edges") {
  // renderShadedElevation computes the tint without rampColour's search and the shade without
  // hillshade()'s raster (maps/render.cpp); every byte must stay what renderLayer draws from
  // terrain::hillshade. Heights on each stop of the ramp (u = 0, ¼, ½, ¾, 1), one float either
  // side of it, below and above the range; flat ground; cliffs (the shade's cosine ≤ 0, and
  // gradients so large x² + y² overflows); NaN and ±inf neighbours; a zero-width cell and a
  // denormal one; in ranges whose stops are exact in float and in ones whose are not.
  const float inf = std::numeric_limits<float>::infinity();
  for (const ColourRange range : {ColourRange{0, 1}, ColourRange{50, 900}, ColourRange{-3.3, 7.1},
                                  ColourRange{1e-7, 3e-7}}) {
    std::vector<float> heights;
    for (int k = 0; k <= 4; ++k) {
      const float h = static_cast<float>(range.lo + (range.hi - range.lo) * 0.25 * k);
      heights.insert(heights.end(), {h, std::nextafter(h, -inf), std::nextafter(h, inf)});
    }
    heights.insert(heights.end(), {static_cast<float>(range.lo - 1e6), static_cast<float>(range.hi + 1e6), 0.0f,
                                   -0.0f, 3e38f, -3e38f, 1e-40f});
    for (const double cell : {1.0, 0.001, 1e6, 0.0, 1e-310}) {
      const int rows = 40, cols = 3 * int(heights.size()) + 6;
      rover::terrain::Dem dem;
      dem.z = Raster<float>(GridGeometry{rows, cols, cell, cell}, 0.0f);
      std::uint32_t seed = 11;
      auto next = [&] {
        seed = seed * 1664525u + 1013904223u;
        return seed >> 8;
      };
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
          const float h = heights[(c / 3) % heights.size()];
          // rows 0-9 flat runs of each height; 10-19 gentle noise; 20-29 cliffs between
          // neighbouring heights (a mix of everything); 30-39 random picks
          dem.z(r, c) = r < 10   ? h
                        : r < 20 ? static_cast<float>(h + 1e-3 * double(next() % 7))
                        : r < 30 ? heights[(c + r) % heights.size()]
                                 : heights[next() % heights.size()];
        }
      for (int k = 0; k < 25; ++k)
        dem.z(1 + int(next() % (rows - 2)), 1 + int(next() % (cols - 2))) =
            k % 3 == 0 ? kNaN : k % 3 == 1 ? inf : -inf;
      const Raster<float> shade = rover::terrain::hillshade(dem);
      RenderOptions options = noLegend();
      options.range = &range;
      RenderInput in;
      in.dem = &dem;
      in.hillshade = &shade;
      const Image expected = renderLayer(RenderLayer::Elevation, in, options);
      const Image fused = renderShadedElevation(dem, range);
      REQUIRE(fused.rgba.size() == expected.rgba.size());
      int different = 0;
      for (std::size_t i = 0; i < fused.rgba.size(); ++i) different += fused.rgba[i] != expected.rgba[i];
      CAPTURE(range.lo);
      CAPTURE(cell);
      CHECK(different == 0);
      const Image greys = renderHillshade(dem);
      CHECK(greys.rgba == renderLayer(RenderLayer::Hillshade, in, noLegend()).rgba);
    }
  }
}

TEST_CASE("overview: the level an overview is drawn from is just larger than it and never over 4096² cells") {
  using rover::maps::overviewStep;
  CHECK(overviewStep(600, 600, 1024) == 1);         // a map no larger than the overview: itself
  CHECK(overviewStep(4000, 4000, 1024) == 2);       // 2000² blocks ≥ 1024 > 1000
  CHECK(overviewStep(15000, 20000, 1024) == 16);    // 938 × 1250: the README's 300 M-cell figure
  // A 4096-px overview of an 8000² map: the side rule alone keeps the full grid (64 M cells); the
  // cell bound halves it to 4000² (16 M).
  CHECK(overviewStep(8000, 8000, 4096) == 2);
  CHECK(overviewStep(8190, 4097, 4096) == 2);
  for (int side : {256, 512, 1024, 2048, 4096})
    for (int n : {300, 4097, 8191, 20000, 100000}) {
      const long long step = overviewStep(n, n, side);
      const long long blocks = (n + step - 1) / step;
      CHECK(blocks * blocks <= rover::maps::kMaxOverviewLevelCells);
    }
}
