// A stored map as its tile pyramid (issue 24, maps/dem_pyramid.hpp): the elevation written as a
// Cloud-Optimised GeoTIFF (tiled, overviews, lossless), the class pyramid with exact worst classes,
// tiles drawn from them equal to the in-memory tiles at the native zoom and within the overview's
// averaging below it, and a map stored before the pyramid (no overviews) read the old way.
#include <doctest/doctest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <future>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/average_levels.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/grid_file.hpp"
#include "maps/map_tiles.hpp"
#include "maps/tile_grid.hpp"

using namespace rover;
using namespace rover::maps;
namespace fs = std::filesystem;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("roverplan-pyramid-" + std::to_string(::getpid()) + "-" + std::to_string(std::rand()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

// Uneven, deterministic heights with a nodata hole and steep ridges (every class appears).
terrain::Dem wavyDem(int rows, int cols, double cell) {
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{rows, cols, cell, cell}, 0.0f);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      dem.z(r, c) = static_cast<float>(6 * std::sin(r * 0.07) + 4 * std::cos(c * 0.045) + 0.002 * r * c +
                                       0.6 * std::sin(r * 1.3 + c * 0.9));
  for (int r = rows / 3; r < rows / 3 + 7; ++r)
    for (int c = cols / 2; c < cols / 2 + 9; ++c) dem.z(r, c) = kNaN;
  return dem;
}

bool sameFloat(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// The stored map's files, as the server writes them at import.
struct StoredMap {
  TempDir dir;
  terrain::Dem dem;
  terrain::Traversability trav;
  std::shared_ptr<const DemHeader> header;
  explicit StoredMap(terrain::Dem d) : dem(std::move(d)), trav(terrain::traversability(dem)) {
    writeDemCog(dir.file("dem.tif"), dem.z);
    writeClassPyramid(dir.file("classes.tif"), trav.classes);
    header = std::make_shared<const DemHeader>(readDemHeader(dir.file("dem.tif")));
  }
  PyramidBlocks blocks() const {
    return PyramidBlocks(dir.file("dem.tif"), dir.file("classes.tif"), header,
                         colourRange(RenderLayer::Elevation, dem.z));
  }
  TileSource memory() const {
    TileSource s;
    s.dem = &dem;
    s.classes = &trav.classes;
    s.range = colourRange(RenderLayer::Elevation, dem.z);
    return s;
  }
};

}  // namespace

TEST_CASE("pyramid: the elevation is a COG of 128² tiles, ZSTD, one overview per zoom below native, values unchanged") {
  StoredMap m(wavyDem(700, 530, 0.5));
  const PyramidInfo info = pyramidInfo(m.dir.file("dem.tif"));
  CHECK(info.layout == "COG");
  CHECK(info.compression == "ZSTD");
  CHECK(info.blockWidth == 128);
  CHECK(info.blockHeight == 128);
  // 700 rows → native zoom 2: overviews of 2 × 2 and 4 × 4 cells, the blocks of zooms 1 and 0
  // (the COG driver rounds 530 / 4 down: 132 where the tile grid has 133 blocks).
  REQUIRE(tileGridOf(700, 530).nativeZoom == 2);
  REQUIRE(info.overviews.size() == 2u);
  CHECK(info.overviews[0] == std::pair{265, 350});
  CHECK(info.overviews[1] == std::pair{132, 175});
  // Lossless: every cell reads back as written, the hole as NaN.
  const LoadedDem back = loadDem(m.dir.file("dem.tif"));
  REQUIRE(back.dem.geometry().rows == 700);
  REQUIRE(back.dem.geometry().cols == 530);
  CHECK(back.dem.geometry().cellWidth == doctest::Approx(0.5));
  for (int i = 0; i < 700 * 530; ++i) REQUIRE(sameFloat(back.dem.z.at(i), m.dem.z.at(i)));
  CHECK(back.info.nodataCells == 63);
  // The class pyramid: tiled, its levels exactly the tile grid's blocks.
  const PyramidInfo classes = pyramidInfo(m.dir.file("classes.tif"));
  CHECK(classes.blockWidth == 256);
  REQUIRE(classes.overviews.size() == 2u);
  CHECK(classes.overviews[0] == std::pair{265, 350});
  CHECK(classes.overviews[1] == std::pair{133, 175});
}

TEST_CASE("pyramid: a map of one tile has no overviews") {
  StoredMap m(wavyDem(200, 130, 1.0));
  CHECK(pyramidInfo(m.dir.file("dem.tif")).overviews.empty());
  CHECK(pyramidInfo(m.dir.file("classes.tif")).overviews.empty());
  const TileGrid g = tileGridOf(200, 130);
  const auto w = tileWindow(g, 0, 0, 0);
  REQUIRE(w);
  const auto stored = tileValues(RenderLayer::Slope, m.blocks(), *w);
  const auto memory = tileValues(RenderLayer::Slope, m.memory(), *w);
  for (std::size_t i = 0; i < stored.size(); ++i) REQUIRE(sameFloat(stored[i], memory[i]));
}

TEST_CASE("pyramid: native-zoom tiles from the stored map are byte for byte the in-memory tiles, every layer") {
  StoredMap m(wavyDem(700, 530, 0.5));
  const TileGrid g = tileGridOf(700, 530);
  const PyramidBlocks stored = m.blocks();
  const TileSource memory = m.memory();
  for (auto layer : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope, RenderLayer::Traversability}) {
    CAPTURE(renderLayerName(layer));
    for (int z : {g.nativeZoom, g.maxZoom()})
      for (auto [x, y] : {std::pair{0, 0}, std::pair{1, 1}, std::pair{tilesAcross(g, z) - 1, tilesDown(g, z) - 1}}) {
        const auto w = tileWindow(g, z, x, y);
        REQUIRE(w);
        CHECK(renderTile(layer, stored, *w).rgba == renderTile(layer, memory, *w).rgba);
      }
  }
  for (auto layer : {RenderLayer::Elevation, RenderLayer::Slope})
    for (int y = 0; y < tilesDown(g, g.nativeZoom); ++y)
      for (int x = 0; x < tilesAcross(g, g.nativeZoom); ++x) {
        const auto w = tileWindow(g, g.nativeZoom, x, y);
        const auto a = tileValues(layer, stored, *w), b = tileValues(layer, memory, *w);
        for (std::size_t i = 0; i < a.size(); ++i) REQUIRE(sameFloat(a[i], b[i]));
      }
}

TEST_CASE("pyramid: below the native zoom, heights come from the overview: the block means where blocks are whole") {
  // 1024 × 768: every block of every zoom is whole, so GDAL's AVERAGE overview is the block mean
  // (up to float rounding) wherever the block has no nodata (a level averages the level above it,
  // so blocks at the hole weigh their cells differently); elsewhere, and on 700 × 530 whose edge
  // blocks are cut, each value must lie within the heights of the cells it stands for and their
  // neighbours' (the overview's resampling window).
  for (const auto& size : {std::pair{1024, 768}, std::pair{700, 530}}) {
    const int rows = size.first, cols = size.second;  // clang 14 cannot capture a structured binding
    CAPTURE(rows);
    StoredMap m(wavyDem(rows, cols, 1.0));
    const TileGrid g = tileGridOf(rows, cols);
    for (int z = 0; z < g.nativeZoom; ++z) {
      const int step = 1 << (g.nativeZoom - z);
      const BlockSpan all{0, 0, (rows + step - 1) / step, (cols + step - 1) / step};
      const terrain::Dem stored = m.blocks().dem(step, all);
      const Raster<float> exact = blockMean(m.dem.z, step, all);
      REQUIRE(stored.z.geometry.rows == all.rows);
      CHECK(stored.z.geometry.cellWidth == doctest::Approx(step));
      int compared = 0;
      for (int i = 0; i < all.rows; ++i)
        for (int j = 0; j < all.cols; ++j) {
          const float v = stored.z(i, j), e = exact(i, j);
          if (std::isnan(e)) continue;  // a block inside the hole
          REQUIRE(std::isfinite(v));
          bool whole = rows == 1024;
          for (int r = i * step; whole && r < (i + 1) * step; ++r)
            for (int c = j * step; whole && c < (j + 1) * step; ++c) whole = std::isfinite(m.dem.z(r, c));
          if (whole) {
            REQUIRE(v == doctest::Approx(e).epsilon(1e-5));
          } else {
            float lo = INFINITY, hi = -INFINITY;
            for (int r = std::max(0, (i - 1) * step); r < std::min(rows, (i + 2) * step); ++r)
              for (int c = std::max(0, (j - 1) * step); c < std::min(cols, (j + 2) * step); ++c)
                if (std::isfinite(m.dem.z(r, c))) lo = std::min(lo, m.dem.z(r, c)), hi = std::max(hi, m.dem.z(r, c));
            REQUIRE(v >= lo - 1e-4f);
            REQUIRE(v <= hi + 1e-4f);
          }
          ++compared;
        }
      CHECK(compared > all.rows * all.cols / 2);
    }
    // Tiles below the native zoom render (no seams asked here: the overview is one raster).
    const auto w = tileWindow(g, 0, 0, 0);
    CHECK(renderTile(RenderLayer::Hillshade, m.blocks(), *w).rgba.size() == 256u * 256u * 4u);
  }
}

TEST_CASE("pyramid: the class levels hold the exact worst class of every block, cut edge blocks included") {
  StoredMap m(wavyDem(700, 530, 0.5));
  const TileGrid g = tileGridOf(700, 530);
  for (int z = 0; z <= g.nativeZoom; ++z) {
    const int step = 1 << (g.nativeZoom - z);
    const BlockSpan all{0, 0, (700 + step - 1) / step, (530 + step - 1) / step};
    const Raster<std::uint8_t> stored = m.blocks().classes(step, all);
    const Raster<std::uint8_t> exact = blockWorstClass(m.trav.classes, step, all);
    CHECK(stored.values == exact.values);
    // A window inside the level reads the same blocks.
    const BlockSpan part{all.rows / 3, all.cols / 4, all.rows / 2, all.cols / 2};
    CHECK(m.blocks().classes(step, part).values == blockWorstClass(m.trav.classes, step, part).values);
  }
  // Not a trivial map: it has impassable cells, and the hole.
  CHECK(m.trav.shares.counts[2] > 0);
  CHECK(m.trav.shares.counts[3] == 63);
}

TEST_CASE("pyramid: a map stored before the pyramid (a tiled GeoTIFF, no overviews) gives the in-memory tiles at every zoom") {
  TempDir dir;
  const terrain::Dem dem = wavyDem(700, 530, 0.5);
  const auto trav = terrain::traversability(dem);
  writeGeoTiff(dir.file("dem.tif"), dem.z);  // the writer maps were stored with before (nodata -9999)
  writeClassesGeoTiff(dir.file("classes.tif"), trav.classes);
  REQUIRE(pyramidInfo(dir.file("dem.tif")).overviews.empty());
  const PyramidBlocks stored(dir.file("dem.tif"), dir.file("classes.tif"),
                             std::make_shared<const DemHeader>(readDemHeader(dir.file("dem.tif"))),
                             colourRange(RenderLayer::Elevation, dem.z));
  TileSource memory;
  memory.dem = &dem;
  memory.classes = &trav.classes;
  memory.range = stored.range();
  const TileGrid g = tileGridOf(700, 530);
  for (int z = 0; z <= g.maxZoom(); ++z)
    for (auto layer : {RenderLayer::Elevation, RenderLayer::Slope, RenderLayer::Traversability}) {
      CAPTURE(z);
      const auto w = tileWindow(g, z, tilesAcross(g, z) - 1, 0);
      REQUIRE(w);
      CHECK(renderTile(layer, stored, *w).rgba == renderTile(layer, memory, *w).rgba);
      if (layer != RenderLayer::Traversability) {
        const auto a = tileValues(layer, stored, *w), b = tileValues(layer, memory, *w);
        for (std::size_t i = 0; i < a.size(); ++i) REQUIRE(sameFloat(a[i], b[i]));
      }
    }
  CHECK_THROWS_AS(stored.pdm(1, BlockSpan{0, 0, 2, 2}), Error);
}

TEST_CASE("pyramid: a geographic map's block rows keep their own widths") {
  TempDir dir;
  terrain::Dem dem = wavyDem(600, 300, 1.0);
  // Ten degrees of latitude near the pole, 0.01° cells: the east-west width shrinks northwards.
  dem.z.geo.valid = true;
  dem.z.geo.geotransform = {10.0, 0.01, 0, 80.0, 0, -0.01};
  dem.z.geo.crsWkt = "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],"
                     "PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433],AUTHORITY[\"EPSG\",\"4326\"]]";
  writeDemCog(dir.file("dem.tif"), dem.z);
  const LoadedDem whole = loadDem(dir.file("dem.tif"));
  REQUIRE(whole.dem.rowCellWidth.size() == 600u);
  const auto header = std::make_shared<const DemHeader>(readDemHeader(dir.file("dem.tif")));
  REQUIRE(header->rowCellWidth == whole.dem.rowCellWidth);
  const BlockSpan span{10, 5, 40, 30};
  const terrain::Dem blocks = PyramidBlocks(dir.file("dem.tif"), "", header, {}).dem(2, span);
  CHECK(blocks.rowCellWidth == blockRowWidths(whole.dem.rowCellWidth, 600, 2, span));
  CHECK(blocks.rowCellWidth.front() < blocks.rowCellWidth.back());  // north is narrower
}

TEST_CASE("pyramid: a stored raster rewritten at the same path is read afresh, not through a kept-open handle") {
  // readDemBlocks keeps open handles between tiles; a file replaced in place (new inode) must be
  // read as it is now, and forgetStoredRasters closes the handles of a deleted map's folder.
  TempDir dir;
  terrain::Dem first = wavyDem(300, 280, 1.0), second = wavyDem(300, 280, 1.0);
  for (int k = 0; k < second.geometry().cellCount(); ++k) second.z.at(k) += 100.0f;
  const BlockSpan span{10, 20, 40, 30};
  writeDemCog(dir.file("dem.tif"), first.z);
  const DemHeader header = readDemHeader(dir.file("dem.tif"));
  const terrain::Dem a = readDemBlocks(dir.file("dem.tif"), header, 1, span);
  CHECK(sameFloat(a.z(0, 0), first.z(10, 20)));
  CHECK(sameFloat(readDemBlocks(dir.file("dem.tif"), header, 1, span).z(5, 5), first.z(15, 25)));  // kept handle
  writeDemCog(dir.file("dem.tif"), second.z);
  const terrain::Dem b = readDemBlocks(dir.file("dem.tif"), header, 1, span);
  for (int r = 0; r < span.rows; ++r)
    for (int c = 0; c < span.cols; ++c) REQUIRE(sameFloat(b.z(r, c), second.z(span.r0 + r, span.c0 + c)));
  forgetStoredRasters(dir.path.string());
  CHECK(sameFloat(readDemBlocks(dir.file("dem.tif"), header, 1, span).z(0, 0), second.z(10, 20)));
}

TEST_CASE("pyramid: a map imported from a grid file (no float copy in memory) gives the same COG and classes") {
  // Odd sizes and bands that do not divide the rows, a nodata hole, and a geographic map's row
  // widths: the band-wise classes equal the whole-grid ones cell for cell, shares included.
  for (const bool geographic : {false, true}) {
    CAPTURE(geographic);
    terrain::Dem dem = wavyDem(533, 401, 0.5);
    if (geographic)
      for (int r = 0; r < 533; ++r) dem.rowCellWidth.push_back(0.5 * std::cos((40.0 + r * 0.01) * 3.14159265 / 180.0));
    TempDir dir;
    const std::string grid = dir.file("grid.f32");
    {
      GridFileWriter w(grid, dem.geometry());
      for (int r0 = 0; r0 < 533; r0 += 100)  // in chunks, as the import streams them
        w.append(&dem.z(r0, 0), static_cast<std::size_t>(std::min(100, 533 - r0)) * 401);
      w.close();
    }
    const terrain::Traversability whole = terrain::traversability(dem);
    for (int band : {1, 7, 256, 600})
      for (unsigned threads : {1u, 2u, 3u}) {
        CAPTURE(band);
        CAPTURE(threads);
        // The bands' cells seen in row order, one band at a time, on any thread count.
        std::vector<float> seen;
        const terrain::Traversability banded = traversabilityOfGridFile(
            grid, dem.geometry(), dem.rowCellWidth, band,
            [&](const float* v, std::size_t n) { seen.insert(seen.end(), v, v + n); }, nullptr, threads);
        CHECK(banded.classes.values == whole.classes.values);
        CHECK(banded.shares.counts == whole.shares.counts);
        REQUIRE(seen.size() == dem.z.values.size());
        CHECK(std::memcmp(seen.data(), dem.z.values.data(), seen.size() * sizeof(float)) == 0);
      }
    writeDemCog(dir.file("memory.tif"), dem.z);
    writeDemCog(dir.file("file.tif"), grid, dem.geometry(), dem.z.geo);
    std::vector<float> rows(3 * 401);
    readGridRows(grid, 401, 200, 3, rows.data());
    CHECK(sameFloat(rows[401 + 5], dem.z(201, 5)));
    std::ifstream a(dir.file("memory.tif"), std::ios::binary), b(dir.file("file.tif"), std::ios::binary);
    const std::string ab((std::istreambuf_iterator<char>(a)), {}), bb((std::istreambuf_iterator<char>(b)), {});
    CHECK(ab.size() > 100000u);
    CHECK(ab == bb);  // byte for byte
  }
}

namespace {

// Heights of mixed magnitudes (the sums' rounding), scattered NaN cells and a whole NaN block in
// the corner (a level pixel with no data).
Raster<float> noisyHeights(int rows, int cols) {
  Raster<float> z(GridGeometry{rows, cols, 1.0, 1.0}, 0.0f);
  std::uint32_t seed = 24;
  float* cells = z.values.data();
  for (std::size_t i = 0, n = static_cast<std::size_t>(z.values.size()); i < n; ++i) {
    float& v = cells[i];
    seed = seed * 1664525u + 1013904223u;
    const float u = static_cast<float>(seed >> 8) / 16777216.0f;
    v = (seed & 3u) == 0 ? u * 0.001f : (u - 0.5f) * 4000.0f;
    if ((seed >> 4) % 97 == 0) v = kNaN;
  }
  for (int r = 0; r < std::min(rows, 40); ++r)
    for (int c = 0; c < std::min(cols, 40); ++c) z(r, c) = kNaN;
  return z;
}

// The reference for a level, written from the definition rather than from GDAL's loops: pixel
// (i, j) of an outRows × outCols level covers [j·cols/outCols, (j + 1)·cols/outCols) ×
// [i·rows/outRows, …) of the level above; each cell weighs the area it shares with that window,
// NaN cells weigh nothing, NaN where nothing is left.
std::vector<float> referenceLevel(const std::vector<float>& src, int rows, int cols, int outRows, int outCols) {
  auto overlap = [](double lo, double hi, int cell) { return std::max(0.0, std::min(hi, cell + 1.0) - std::max(lo, double(cell))); };
  const double ry = double(rows) / outRows, rx = double(cols) / outCols;
  std::vector<float> out(static_cast<std::size_t>(outRows) * outCols);
  for (int i = 0; i < outRows; ++i)
    for (int j = 0; j < outCols; ++j) {
      double sum = 0, weight = 0;
      for (int r = static_cast<int>(i * ry); r < std::min(rows, static_cast<int>(std::ceil((i + 1) * ry))); ++r)
        for (int c = static_cast<int>(j * rx); c < std::min(cols, static_cast<int>(std::ceil((j + 1) * rx))); ++c) {
          const float v = src[static_cast<std::size_t>(r) * cols + c];
          const double w = overlap(i * ry, (i + 1) * ry, r) * overlap(j * rx, (j + 1) * rx, c);
          if (std::isnan(v) || w <= 0) continue;
          sum += w * v;
          weight += w;
        }
      out[static_cast<std::size_t>(i) * outCols + j] = weight > 0 ? static_cast<float>(sum / weight) : kNaN;
    }
  return out;
}

// `z` as the server's grid file at `path` (what the import hands the COG writer); returns `path`.
std::string writeGrid(const std::string& path, const Raster<float>& z) {
  GridFileWriter w(path, z.geometry);
  w.append(z.values.data(), static_cast<std::size_t>(z.values.size()));
  w.close();
  return path;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace

TEST_CASE("pyramid: every overview level is the nodata-aware average of the level above, on 1 and 2 threads") {
  // maps/average_levels.hpp on any shape against the reference above: levels that halve evenly,
  // oddly on one side or both (cut cells at the raster's own edge weighted by the part inside),
  // strips whose short side reaches one row, more rows than one band of 64 level rows. On large
  // maps with odd level sizes these are the levels dem.tif gets even where GDAL's own differ (at
  // the ends of its chunks of rows), so they are checked here against the definition, not GDAL.
  const int shapes[][2] = {{533, 1101}, {777, 1031}, {1001, 999}, {3, 1500}, {1300, 5}, {256, 384}};
  for (const auto& shape : shapes) {
    const int rows = shape[0], cols = shape[1];
    CAPTURE(rows);
    CAPTURE(cols);
    const Raster<float> z = noisyHeights(rows, cols);
    TempDir dir;
    const std::string grid = writeGrid(dir.file("grid.f32"), z);
    const std::vector<LevelFile> one = writeAverageLevels(grid, rows, cols, 5, dir.file("one-"), 1);
    const std::vector<LevelFile> two = writeAverageLevels(grid, rows, cols, 5, dir.file("two-"), 2);
    REQUIRE(one.size() == 5u);
    REQUIRE(two.size() == 5u);
    std::vector<float> above(z.values.data(), z.values.data() + z.values.size());
    int aboveRows = rows, aboveCols = cols;
    for (std::size_t k = 0; k < one.size(); ++k) {
      CAPTURE(k + 1);
      CHECK(one[k].rows == std::max(1, aboveRows / 2));
      CHECK(one[k].cols == std::max(1, aboveCols / 2));
      CHECK(fileBytes(one[k].path) == fileBytes(two[k].path));  // the same bytes on any thread count
      std::vector<float> level(static_cast<std::size_t>(one[k].rows) * one[k].cols);
      readGridRows(one[k].path, one[k].cols, 0, one[k].rows, level.data());
      const std::vector<float> expected = referenceLevel(above, aboveRows, aboveCols, one[k].rows, one[k].cols);
      std::size_t wrong = 0, nans = 0;
      for (std::size_t i = 0; i < level.size(); ++i) {
        nans += std::isnan(expected[i]);
        // The reference sums in another order: equal up to the float's last bits.
        const bool same = std::isnan(expected[i]) ? std::isnan(level[i])
                                                  : std::fabs(level[i] - expected[i]) <= 1e-5f * std::max(1.0f, std::fabs(expected[i]));
        wrong += !same;
      }
      CHECK(wrong == 0u);
      if (k == 0 && rows >= 80 && cols >= 80) CHECK(nans > 0u);  // the NaN block reached the level
      above = std::move(level);
      aboveRows = one[k].rows;
      aboveCols = one[k].cols;
    }
  }
}

TEST_CASE("pyramid: overview levels that fail part-way leave no level file behind") {
  // A grid file 100 rows short of the 600 its caller names: level 1's bands past the file's end
  // fail to read after the first bands were written. Before, level files stayed beside the grid.
  const Raster<float> z = noisyHeights(500, 700);
  TempDir dir;
  const std::string grid = writeGrid(dir.file("grid.f32"), z);
  CHECK_THROWS_AS(writeAverageLevels(grid, 600, 700, 4, dir.file("level-"), 2), GridFileError);
  int left = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path))
    left += e.path().filename().string().rfind("level-", 0) == 0;
  CHECK(left == 0);
  // The grid itself is the caller's: still there, and a call on its true size makes every level.
  CHECK(std::filesystem::exists(grid));
  CHECK(writeAverageLevels(grid, 500, 700, 4, dir.file("level-"), 2).size() == 4u);
}

TEST_CASE("pyramid: where GDAL cuts no averaging window, the COG's levels are GDAL's own, bit for bit") {
  // maps/average_levels.hpp inside the COG against the COG driver's own levels (the in-memory
  // writer lets GDAL compute them), on maps small enough that GDAL reads each level in one chunk of
  // rows (so no window is clipped at a chunk's end), and on even shapes, whose every window is its
  // own 2 × 2 cells: shapes whose levels halve evenly, oddly on one side or both (weighted cut
  // cells), a strip whose short side reaches one row, the NaN cells and block of noisyHeights.
  const int shapes[][2] = {{1024, 1536}, {2048, 512}, {533, 1101}, {777, 1031}, {3, 1500}, {1300, 5}};
  for (const auto& shape : shapes) {
    const int rows = shape[0], cols = shape[1];
    CAPTURE(rows);
    CAPTURE(cols);
    const Raster<float> z = noisyHeights(rows, cols);
    TempDir dir;
    const std::string grid = writeGrid(dir.file("grid.f32"), z);
    writeDemCog(dir.file("memory.tif"), z);
    writeDemCog(dir.file("file.tif"), grid, z.geometry, z.geo);
    CHECK(pyramidInfo(dir.file("file.tif")).overviews == pyramidInfo(dir.file("memory.tif")).overviews);
    std::ifstream a(dir.file("memory.tif"), std::ios::binary), b(dir.file("file.tif"), std::ios::binary);
    const std::string ab((std::istreambuf_iterator<char>(a)), {}), bb((std::istreambuf_iterator<char>(b)), {});
    CHECK(ab == bb);  // byte for byte
    // The levels' files are gone with the import's scratch: only the two COGs and the grid remain.
    CHECK(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()) == 3);
  }
}

TEST_CASE("grid file: classes computed while the rows are written wait for them, and stop when the stream fails") {
  terrain::Dem dem = wavyDem(533, 401, 0.5);
  const terrain::Traversability whole = terrain::traversability(dem);
  TempDir dir;
  const std::string grid = dir.file("grid.f32");
  SUBCASE("the rows arrive in chunks: the same classes and shares as the whole grid's") {
    GridRowsGate gate;
    GridFileWriter w(grid, dem.geometry());
    auto classes = std::async(std::launch::async, [&] {
      return traversabilityOfGridFile(grid, dem.geometry(), {}, 64, {}, &gate, 2);
    });
    for (int r0 = 0; r0 < 533; r0 += 100) {
      const int n = std::min(100, 533 - r0);
      w.append(&dem.z(r0, 0), static_cast<std::size_t>(n) * 401);
      w.flush();
      gate.publish(r0 + n);
    }
    w.close();
    const terrain::Traversability t = classes.get();
    CHECK(t.classes.values == whole.classes.values);
    CHECK(t.shares.counts == whole.shares.counts);
  }
  SUBCASE("the stream fails half way: the waiting thread ends with GridFileError") {
    GridRowsGate gate;
    GridFileWriter w(grid, dem.geometry());
    auto classes = std::async(std::launch::async, [&] {
      // Two threads, one band in turn for the digest: a band past the stream's end must not
      // leave the other waiting for its turn.
      return traversabilityOfGridFile(grid, dem.geometry(), {}, 64, [](const float*, std::size_t) {}, &gate, 2);
    });
    w.append(&dem.z(0, 0), 200u * 401);
    w.flush();
    gate.publish(200);
    gate.abort();
    CHECK_THROWS_AS(classes.get(), GridFileError);
  }
}
