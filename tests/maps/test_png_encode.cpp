// PNG encoding (issue 24, cold tiles): PngColours::Smallest picks grey, a palette (1-8 bits), RGB
// or RGBA and always decodes (with GDAL, i.e. libpng and zlib) to exactly the image's RGBA; the
// literal-only deflate stream (maps/literal_deflate.hpp) inflates to its input.
#include <cpl_vsi.h>
#include <doctest/doctest.h>
#include <gdal.h>
#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/terrain/layers.hpp"
#include "maps/gdal_env.hpp"
#include "maps/literal_deflate.hpp"
#include "maps/map_tiles.hpp"
#include "maps/render.hpp"
#include "tile_fixtures.hpp"

using namespace rover;
using namespace rover::maps;

namespace {

// RGBA as GDAL decodes `png` (a palette expanded with its tRNS alphas, grey repeated, no alpha
// band: opaque); empty when GDAL cannot read it.
std::vector<std::uint8_t> decodeRgba(const std::vector<std::uint8_t>& png, int& width, int& height) {
  ensureGdal();
  static int counter = 0;
  const std::string path = "/vsimem/test_png_encode_" + std::to_string(counter++) + ".png";
  VSIFCloseL(VSIFileFromMemBuffer(path.c_str(), const_cast<GByte*>(png.data()), png.size(), FALSE));
  GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  std::vector<std::uint8_t> rgba;
  if (ds != nullptr) {
    width = GDALGetRasterXSize(ds);
    height = GDALGetRasterYSize(ds);
    const int bands = GDALGetRasterCount(ds);
    const std::size_t n = std::size_t(width) * height;
    rgba.assign(n * 4, 255);
    std::vector<std::uint8_t> band(n);
    for (int b = 1; b <= bands; ++b) {
      GDALRasterBandH hb = GDALGetRasterBand(ds, b);
      if (GDALRasterIO(hb, GF_Read, 0, 0, width, height, band.data(), width, height, GDT_Byte, 0, 0) != CE_None) {
        rgba.clear();
        break;
      }
      GDALColorTableH ct = GDALGetRasterColorTable(hb);
      for (std::size_t i = 0; i < n; ++i) {
        if (ct != nullptr) {
          const GDALColorEntry* e = GDALGetColorEntry(ct, band[i]);
          rgba[i * 4] = static_cast<std::uint8_t>(e->c1);
          rgba[i * 4 + 1] = static_cast<std::uint8_t>(e->c2);
          rgba[i * 4 + 2] = static_cast<std::uint8_t>(e->c3);
          rgba[i * 4 + 3] = static_cast<std::uint8_t>(e->c4);
        } else if (bands == 1) {
          rgba[i * 4] = rgba[i * 4 + 1] = rgba[i * 4 + 2] = band[i];
        } else {
          rgba[i * 4 + b - 1] = band[i];
        }
      }
    }
    GDALClose(ds);
  }
  VSIUnlink(path.c_str());
  return rgba;
}

struct Encoded {
  int colourType = -1, bitDepth = -1;
  std::size_t bytes = 0;
};

// Encodes `img` with Smallest and checks that it decodes to the same pixels.
Encoded roundTrip(const Image& img) {
  const auto png = encodePng(img, PngColours::Smallest);
  REQUIRE(png.size() > 33);
  int w = 0, h = 0;
  const auto back = decodeRgba(png, w, h);
  REQUIRE(!back.empty());
  CHECK(w == img.width);
  CHECK(h == img.height);
  CHECK(back == img.rgba);
  return {png[25], png[24], png.size()};
}

Image picture(int w, int h) {
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(std::size_t(w) * h * 4, 0);
  return img;
}

void set(Image& img, int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b, std::uint8_t a) {
  std::uint8_t* p = &img.rgba[(std::size_t(y) * img.width + x) * 4];
  p[0] = r, p[1] = g, p[2] = b, p[3] = a;
}

}  // namespace

TEST_CASE("png: Smallest picks grey, a palette of 1-8 bits, RGB or RGBA, each decoding to the same RGBA") {
  // Opaque greys (a hillshade inside the map): 8-bit grey.
  Image grey = picture(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const auto v = static_cast<std::uint8_t>(1 + (x * 7 + y * 3) % 255);  // never 0 (as hillshade)
      set(grey, x, y, v, v, v, 255);
    }
  auto e = roundTrip(grey);
  CHECK(e.colourType == 0);
  CHECK(e.bitDepth == 8);

  // Greys and transparent cells (a hillshade at the map's edge): a palette with tRNS.
  for (int y = 200; y < 256; ++y)
    for (int x = 0; x < 256; ++x) set(grey, x, y, 0, 0, 0, 0);
  for (int x = 0; x < 256; ++x) set(grey, x, 0, static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(x), 255);
  set(grey, 0, 0, 1, 1, 1, 255);  // 255 opaque greys and transparent: 256 colours
  e = roundTrip(grey);
  CHECK(e.colourType == 3);
  CHECK(e.bitDepth == 8);

  // Few colours, translucent ones among them, on odd widths: 1, 2 and 4 bits a pixel, rows
  // ending inside a byte.
  const std::uint8_t classes[4][4] = {{50, 170, 80, 255}, {255, 176, 0, 255}, {215, 35, 35, 255}, {40, 40, 40, 160}};
  for (int colours : {2, 4, 13}) {
    for (int w : {1, 3, 37}) {
      Image img = picture(w, 11);
      for (int y = 0; y < 11; ++y)
        for (int x = 0; x < w; ++x) {
          const int k = (x * 5 + y * 3) % colours;
          if (k < 4) set(img, x, y, classes[k][0], classes[k][1], classes[k][2], classes[k][3]);
          else set(img, x, y, static_cast<std::uint8_t>(k * 19), 7, static_cast<std::uint8_t>(250 - k), 255);
        }
      CAPTURE(colours);
      CAPTURE(w);
      e = roundTrip(img);
      CHECK(e.colourType == 3);
      const int used = std::min(colours, w * 11);
      CHECK(e.bitDepth == (used <= 2 ? 1 : used <= 4 ? 2 : 4));
    }
  }

  // More than 256 colours, all opaque: RGB, from noise-like rows (literal blocks) and from a
  // picture that is mostly one colour (runs: deflate's matches).
  std::mt19937 rng(7);
  Image noisy = picture(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x)
      set(noisy, x, y, static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(y + (rng() & 7)), 255);
  e = roundTrip(noisy);
  CHECK(e.colourType == 2);
  Image flat = picture(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) set(flat, x, y, 90, 120, 60, 255);
  for (int x = 0; x < 256; ++x) set(flat, x, 17, static_cast<std::uint8_t>(x), 3, 200, 255);
  for (int x = 0; x < 256; ++x) set(flat, x, 18, static_cast<std::uint8_t>(x), 4, 100, 255);
  e = roundTrip(flat);
  CHECK(e.colourType == 2);
  CHECK(e.bytes < 4000);  // the runs compressed, not a bit a byte

  // More than 256 colours and some transparent: RGBA.
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 256; ++x) set(noisy, x, y, 0, 0, 0, 0);
  e = roundTrip(noisy);
  CHECK(e.colourType == 6);

  // A single pixel, opaque and not.
  Image one = picture(1, 1);
  set(one, 0, 0, 10, 20, 30, 255);
  CHECK(roundTrip(one).colourType == 3);
  set(one, 0, 0, 0, 0, 0, 0);
  CHECK(roundTrip(one).colourType == 3);

  // RGBA (the default, whole-map pictures) is unchanged: colour type 6.
  CHECK(encodePng(grey)[25] == 6);
}

TEST_CASE("png: every layer's tile, encoded as tiles are, decodes to the rendered RGBA") {
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{300, 530, 0.5, 0.5}, 0.0f);
  for (int r = 0; r < 300; ++r)
    for (int c = 0; c < 530; ++c)
      dem.z(r, c) = static_cast<float>(6 * std::sin(r * 0.07) + 4 * std::cos(c * 0.045) + 0.002 * r * c +
                                       0.6 * std::sin(r * 1.3 + c * 0.9));
  for (int r = 100; r < 107; ++r)
    for (int c = 265; c < 274; ++c) dem.z(r, c) = std::numeric_limits<float>::quiet_NaN();
  const auto trav = terrain::traversability(dem);
  const Raster<float> mass = test::massBump(dem.geometry(), 150, 300, 8000.0);
  TileSource src = test::tileSourceOf(dem, trav.classes, mass);
  const TileGrid g = tileGridOf(300, 530);
  int types = 0;
  for (auto layer : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope, RenderLayer::Traversability,
                     RenderLayer::Pdm}) {
    CAPTURE(renderLayerName(layer));
    src.range = colourRange(layer, layer == RenderLayer::Pdm ? mass : dem.z);
    for (int z = 0; z <= g.maxZoom(); ++z)
      for (int y = 0; y < tilesDown(g, z); ++y)
        for (int x = 0; x < tilesAcross(g, z); ++x) {
          CAPTURE(z);
          CAPTURE(x);
          CAPTURE(y);
          types |= 1 << roundTrip(renderTile(layer, src, *tileWindow(g, z, x, y))).colourType;
        }
  }
  CHECK((types & (1 << 3)) != 0);  // the palette is used (classes, hillshade)
}

TEST_CASE("literal deflate: streams inflate to their input (empty, one value, skewed counts, several blocks)") {
  auto check = [](const std::vector<std::uint8_t>& in) {
    std::vector<std::uint8_t> z = {0xAB};  // appended after what is there
    REQUIRE(literalZlib(in.data(), in.size(), z));
    CHECK(z[0] == 0xAB);
    std::vector<std::uint8_t> out(in.size() + 1);
    std::size_t got = 0;
    libdeflate_decompressor* d = libdeflate_alloc_decompressor();
    const auto rc = libdeflate_zlib_decompress(d, z.data() + 1, z.size() - 1, out.data(), out.size(), &got);
    libdeflate_free_decompressor(d);
    REQUIRE(rc == LIBDEFLATE_SUCCESS);
    out.resize(got);
    CHECK(out == in);
    // zlib's inflate too (the decoder browsers and most PNG readers descend from), which also
    // checks the Adler-32.
    std::vector<std::uint8_t> inflated(in.size() + 1);
    uLongf inflatedSize = inflated.size();
    REQUIRE(uncompress(inflated.data(), &inflatedSize, z.data() + 1, z.size() - 1) == Z_OK);
    inflated.resize(inflatedSize);
    CHECK(inflated == in);
    return z.size() - 1;
  };
  check({});
  check({42});
  CHECK(check(std::vector<std::uint8_t>(100000, 7)) < 100000 / 8 + 400);  // a bit a byte
  // Counts in a Fibonacci sequence: an unlimited Huffman tree would be 25 deep (deflate: 15).
  std::vector<std::uint8_t> skewed;
  std::uint32_t a = 1, b = 1;
  for (int v = 0; v < 26; ++v) {
    skewed.insert(skewed.end(), a, static_cast<std::uint8_t>(v));
    const std::uint32_t next = a + b;
    a = b;
    b = next;
  }
  std::shuffle(skewed.begin(), skewed.end(), std::mt19937(3));
  check(skewed);
  // Three blocks of every byte value, in random order.
  std::vector<std::uint8_t> random(2'500'000);
  std::mt19937 rng(11);
  for (auto& v : random) v = static_cast<std::uint8_t>(rng());
  CHECK(check(random) < random.size() + random.size() / 1000);  // incompressible: a header a block
  // The 1 MiB block edge: one byte short of a block, exactly one (no empty block after it), one
  // byte over (a last block of a single byte value and end-of-block), exactly two. The two blocks'
  // bytes differ (values 0..15, then 200..255), so each block needs its own code.
  constexpr std::size_t kMiB = std::size_t(1) << 20;
  for (const std::size_t n : {kMiB - 1, kMiB, kMiB + 1, 2 * kMiB}) {
    CAPTURE(n);
    std::vector<std::uint8_t> edge(n);
    for (std::size_t i = 0; i < n; ++i)
      edge[i] = static_cast<std::uint8_t>(i < kMiB ? rng() % 16 : 200 + rng() % 56);
    // Each block coded for its own bytes: about 4 bits a byte in the first, 6 in the second.
    CHECK(check(edge) < std::min(n, kMiB) * 9 / 16 + (n > kMiB ? n - kMiB : 0) * 6 / 8 + 1000);
  }
  // Too common a byte value: nothing written.
  std::vector<std::uint8_t> out = {1, 2};
  std::vector<std::uint8_t> runs(1000, 0);
  runs[3] = 9;
  CHECK_FALSE(literalZlib(runs.data(), runs.size(), out, 0.5));
  CHECK(out == std::vector<std::uint8_t>{1, 2});
}
