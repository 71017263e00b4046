// Tiles of a map (issue 24): addressing on literal grids, tiles equal to the crop of the whole-map
// picture at the native zoom, no seams at tile edges (the 3×3 kernel's halo), hostile addresses.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/terrain/layers.hpp"
#include "maps/map_tiles.hpp"
#include "maps/tile_grid.hpp"
#include "tile_fixtures.hpp"

using namespace rover;
using namespace rover::maps;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// An uneven, deterministic DEM with a nodata hole, `rows` × `cols` cells of `cell` metres.
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

// The tile's pixel (px, py) is map cell (row, col) at the native zoom.
void checkTileIsCrop(const Image& whole, const Image& tile, const TileWindow& w, int& compared) {
  for (int py = 0; py < kTileSize; ++py)
    for (int px = 0; px < kTileSize; ++px) {
      const int row = w.blockRow0 + py, col = w.blockCol0 + px;
      const std::uint8_t* t = &tile.rgba[(std::size_t(py) * kTileSize + px) * 4];
      if (py >= w.blockRows || px >= w.blockCols) {  // beyond the map: transparent
        REQUIRE(t[3] == 0);
        continue;
      }
      const std::uint8_t* m = &whole.rgba[(std::size_t(row) * whole.width + col) * 4];
      REQUIRE_MESSAGE(std::memcmp(t, m, 4) == 0, "tile " << w.x << "," << w.y << " pixel " << px << "," << py);
      ++compared;
    }
}

}  // namespace

TEST_CASE("tiles: addressing on literal grids (one tile, odd sizes, partial edge tiles, magnified zooms)") {
  // A single cell: one tile at every zoom, the cell magnified 1, 2 and 4 times.
  TileGrid one = tileGridOf(1, 1);
  CHECK(one.nativeZoom == 0);
  CHECK(one.maxZoom() == 2);
  for (int z = 0; z <= 2; ++z) {
    auto w = tileWindow(one, z, 0, 0);
    REQUIRE(w);
    CHECK(w->step == 1);
    CHECK(w->magnify == (1 << z));
    CHECK((w->blockRows == 1 && w->blockCols == 1));
    CHECK(!tileWindow(one, z, 1, 0));
    CHECK(!tileWindow(one, z, 0, 1));
  }
  // 256 fits one tile at native zoom 0; 257 needs zoom 1 to show one cell per pixel.
  CHECK(tileGridOf(256, 256).nativeZoom == 0);
  CHECK(tileGridOf(257, 10).nativeZoom == 1);
  CHECK(tileGridOf(10, 257).nativeZoom == 1);

  // 1001 rows × 333 columns: native zoom 2 (1024 ≥ 1001).
  TileGrid g = tileGridOf(1001, 333);
  REQUIRE(g.nativeZoom == 2);
  CHECK(g.maxZoom() == 4);
  // z = 0: the whole map in one tile, blocks of 4 × 4 cells, the last ones cut by the edge.
  auto z0 = tileWindow(g, 0, 0, 0);
  REQUIRE(z0);
  CHECK(z0->step == 4);
  CHECK(z0->blocksDown == 251);   // ceil(1001 / 4)
  CHECK(z0->blocksAcross == 84);  // ceil(333 / 4)
  CHECK((z0->blockRows == 251 && z0->blockCols == 84));
  CHECK(tilesAcross(g, 0) == 1);
  CHECK(tilesDown(g, 0) == 1);
  // z = 1: 2 × 2 blocks; 501 × 167 blocks in 2 × 1 tiles.
  CHECK(tilesDown(g, 1) == 2);
  CHECK(tilesAcross(g, 1) == 1);
  auto z1 = tileWindow(g, 1, 0, 1);
  REQUIRE(z1);
  CHECK((z1->blockRow0 == 256 && z1->blockRows == 245 && z1->blockCols == 167));
  // Native zoom: 4 × 2 tiles, the last row 1001 − 768 = 233 cells, the last column 77.
  CHECK(tilesDown(g, 2) == 4);
  CHECK(tilesAcross(g, 2) == 2);
  auto edge = tileWindow(g, 2, 1, 3);
  REQUIRE(edge);
  CHECK((edge->step == 1 && edge->magnify == 1));
  CHECK((edge->blockRow0 == 768 && edge->blockCol0 == 256));
  CHECK((edge->blockRows == 233 && edge->blockCols == 77));
  // Native + 1: each cell 2 × 2 pixels, 128 cells a tile; 8 × 3 tiles.
  CHECK(tilesDown(g, 3) == 8);
  CHECK(tilesAcross(g, 3) == 3);
  auto mag = tileWindow(g, 3, 2, 7);
  REQUIRE(mag);
  CHECK(mag->magnify == 2);
  CHECK((mag->blockRow0 == 896 && mag->blockRows == 105));
  CHECK((mag->blockCol0 == 256 && mag->blockCols == 77));
  // Native + 2: 4 × 4 pixels a cell.
  auto deepest = tileWindow(g, 4, 5, 15);
  REQUIRE(deepest);
  CHECK(deepest->magnify == 4);
  CHECK((deepest->blockRow0 == 960 && deepest->blockRows == 41));
  CHECK((deepest->blockCol0 == 320 && deepest->blockCols == 13));
}

TEST_CASE("tiles: hostile addresses name no tile") {
  TileGrid g = tileGridOf(1001, 333);
  for (const auto& zxy : std::vector<std::array<long long, 3>>{
           {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}, {5, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 2, 0}, {2, 0, 4},
           {4, 6, 0}, {4, 0, 16}, {1LL << 40, 0, 0}, {2, 1LL << 40, 0}, {2, 0, 999999999},
           {std::numeric_limits<long long>::max(), 0, 0}, {2, std::numeric_limits<long long>::min(), 0}}) {
    const long long z = zxy[0], x = zxy[1], y = zxy[2];  // clang 14 cannot capture a structured binding
    CHECK_MESSAGE(!tileWindow(g, z, x, y), z << "/" << x << "/" << y);
  }
}

TEST_CASE("tiles: at the native zoom a tile is byte for byte the crop of the whole-map picture, every layer") {
  const terrain::Dem dem = wavyDem(300, 530, 0.5);
  const auto shade = terrain::hillshade(dem), slope = terrain::slopeHorn(dem);
  const auto trav = terrain::traversability(dem);
  const Raster<float> mass = test::massBump(dem.geometry(), 150, 300, 8000.0);
  TileSource src = test::tileSourceOf(dem, trav.classes, mass);
  const TileGrid g = tileGridOf(300, 530);
  REQUIRE(g.nativeZoom == 2);
  RenderOptions whole;
  whole.legend = false;
  for (auto layer : {RenderLayer::Elevation, RenderLayer::Hillshade, RenderLayer::Slope, RenderLayer::Traversability,
                     RenderLayer::Pdm}) {
    CAPTURE(renderLayerName(layer));
    RenderInput in;
    in.dem = &dem;
    in.hillshade = &shade;
    in.slopeDeg = &slope;
    in.classes = &trav.classes;
    in.pdm = &mass;
    // The whole map at full size with its own (default) colour range; tiles get the same range
    // from colourRange, as the server computes it once per map.
    const Image pic = renderLayer(layer, in, whole);
    src.range = colourRange(layer, layer == RenderLayer::Pdm ? mass : dem.z);
    int compared = 0;
    for (int y = 0; y < tilesDown(g, 2); ++y)
      for (int x = 0; x < tilesAcross(g, 2); ++x) {
        auto w = tileWindow(g, 2, x, y);
        REQUIRE(w);
        checkTileIsCrop(pic, renderTile(layer, src, *w), *w, compared);
      }
    CHECK(compared == 300 * 530);  // every cell of the map in exactly one tile
  }
}

TEST_CASE("tiles: slope at tile edges equals the whole map's (the halo), at the native and magnified zooms") {
  const terrain::Dem dem = wavyDem(300, 530, 0.5);
  const auto slope = terrain::slopeHorn(dem);
  TileSource src;
  src.dem = &dem;
  const TileGrid g = tileGridOf(300, 530);
  for (int z : {g.nativeZoom, g.nativeZoom + 1, g.nativeZoom + 2}) {
    int edges = 0;
    for (int y = 0; y < tilesDown(g, z); ++y)
      for (int x = 0; x < tilesAcross(g, z); ++x) {
        auto w = tileWindow(g, z, x, y);
        REQUIRE(w);
        const auto values = tileValues(RenderLayer::Slope, src, *w);
        const auto heights = tileValues(RenderLayer::Elevation, src, *w);
        for (int py = 0; py < kTileSize; ++py)
          for (int px = 0; px < kTileSize; ++px) {
            const float v = values[std::size_t(py) * kTileSize + px];
            const int br = py / w->magnify, bc = px / w->magnify;
            if (br >= w->blockRows || bc >= w->blockCols) {
              REQUIRE(std::isnan(v));
              continue;
            }
            const int row = w->blockRow0 + br, col = w->blockCol0 + bc;
            REQUIRE_MESSAGE(sameFloat(v, slope(row, col)), "z " << z << " cell " << row << "," << col);
            REQUIRE(sameFloat(heights[std::size_t(py) * kTileSize + px], dem.z(row, col)));
            // A cell on a tile's edge that is inside the map has its slope (no NaN seam).
            const bool tileEdge = br == 0 || bc == 0 || br == w->blockRows - 1 || bc == w->blockCols - 1;
            const bool mapEdge = row == 0 || col == 0 || row == 299 || col == 529;
            if (tileEdge && !mapEdge && std::isfinite(slope(row, col))) {
              CHECK(std::isfinite(v));
              ++edges;
            }
          }
      }
    CHECK(edges > 1000);
  }
}

TEST_CASE("tiles: below the native zoom, slope is the block-mean DEM's, seamless across tiles") {
  const terrain::Dem dem = wavyDem(300, 530, 0.5);
  // The map averaged over 2 × 2 blocks by hand (z = native − 1), then its slope on 1 m cells.
  terrain::Dem coarse;
  coarse.z = Raster<float>(GridGeometry{150, 265, 1.0, 1.0}, kNaN);
  for (int i = 0; i < 150; ++i)
    for (int j = 0; j < 265; ++j) {
      double sum = 0;
      int n = 0;
      for (int r = 2 * i; r < 2 * i + 2; ++r)
        for (int c = 2 * j; c < 2 * j + 2; ++c)
          if (std::isfinite(dem.z(r, c))) {
            sum += dem.z(r, c);
            ++n;
          }
      if (n) coarse.z(i, j) = static_cast<float>(sum / n);
    }
  const auto expected = terrain::slopeHorn(coarse);
  TileSource src;
  src.dem = &dem;
  const TileGrid g = tileGridOf(300, 530);
  REQUIRE(tilesAcross(g, 1) == 2);  // 265 blocks: the seam between the two tiles is at block 256
  for (int x = 0; x < 2; ++x) {
    auto w = tileWindow(g, 1, x, 0);
    REQUIRE(w);
    CHECK(w->step == 2);
    const auto values = tileValues(RenderLayer::Slope, src, *w);
    for (int br = 0; br < w->blockRows; ++br)
      for (int bc = 0; bc < w->blockCols; ++bc)
        REQUIRE(sameFloat(values[std::size_t(br) * kTileSize + bc], expected(br, w->blockCol0 + bc)));
  }
}

TEST_CASE("tiles: a geographic map's per-row cell widths follow the window") {
  terrain::Dem dem = wavyDem(300, 280, 1.0);
  dem.rowCellWidth.resize(300);
  for (int r = 0; r < 300; ++r) dem.rowCellWidth[r] = 0.7 + 0.001 * r;  // narrower cells towards the top
  const auto slope = terrain::slopeHorn(dem);
  TileSource src;
  src.dem = &dem;
  const TileGrid g = tileGridOf(300, 280);
  auto w = tileWindow(g, g.nativeZoom, 0, 1);
  REQUIRE(w);
  const auto values = tileValues(RenderLayer::Slope, src, *w);
  for (int br = 0; br < w->blockRows; ++br)
    for (int bc = 0; bc < w->blockCols; ++bc)
      REQUIRE(sameFloat(values[std::size_t(br) * kTileSize + bc], slope(w->blockRow0 + br, bc)));
}
