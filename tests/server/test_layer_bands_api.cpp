// Full-size layer files of a map over the whole-layer size (issue 24: a HiRISE DTM's slope as a
// GeoTIFF for QGIS): made band by band from the stored DEM (maps/layer_bands.hpp), and cell for
// cell what the whole-map path makes of the same map, from the raw VRT as from the COG.
#include <doctest/doctest.h>

#include <gdal.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/gdal_env.hpp"
#include "tests/wait_until.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::ApiServerOptions;
using rover::test::checkError;
using rover::test::TempDir;
using nlohmann::json;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kRows = 613, kCols = 389;  // three bands of 256 rows, the last one cut

// Whether (r, c) of the test map has no height: a hole across the first band boundary (rows
// 250..261), two single cells on its two sides (rows 255 and 256), and runs along every edge
// of the map (top-left corner, the last row's right part, the last column's lower part).
bool hole(int r, int c) {
  return (r >= 250 && r < 262 && c >= 100 && c < 150) || (r == 255 && c == 300) || (r == 256 && c == 200) ||
         (r < 20 && c < 3) || (r == kRows - 1 && c >= 300) || (c == kCols - 1 && r >= 500);
}

// The test map as a GeoTIFF (1 m cells, UTM 33N): rolling ground whose slope differs everywhere.
std::string testDem(const TempDir& tmp) {
  Raster<float> z(GridGeometry{kRows, kCols, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c)
      z(r, c) = hole(r, c) ? kNaN
                           : static_cast<float>(20 * std::sin(0.031 * c) * std::cos(0.027 * r) + 0.013 * c * r / 50.0 +
                                                0.3 * std::sin(1.7 * c + 0.9 * r));
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100613, 0, -1};
  z.geo.crsWkt = "EPSG:32633";
  maps::writeGeoTiff(tmp.str("bands.tif"), z);
  std::ifstream in(tmp.str("bands.tif"), std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A GeoTIFF's band 1 as floats with its nodata value and georeferencing.
struct Tif {
  int rows = 0, cols = 0;
  std::vector<float> values;
  bool hasNodata = false;
  double nodata = 0;
  std::array<double, 6> gt{};
  std::string wkt;
};

Tif readTif(const std::string& path) {
  maps::ensureGdal();
  Tif t;
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
  REQUIRE(ds != nullptr);
  t.rows = GDALGetRasterYSize(ds);
  t.cols = GDALGetRasterXSize(ds);
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  t.values.resize(static_cast<std::size_t>(t.rows) * t.cols);
  CHECK(GDALRasterIO(band, GF_Read, 0, 0, t.cols, t.rows, t.values.data(), t.cols, t.rows, GDT_Float32, 0, 0) ==
        CE_None);
  int has = 0;
  t.nodata = GDALGetRasterNoDataValue(band, &has);
  t.hasNodata = has != 0;
  GDALGetGeoTransform(ds, t.gt.data());
  t.wkt = GDALGetProjectionRef(ds);
  GDALClose(ds);
  return t;
}

using Hold = rover::test::CompressionHold;

}  // namespace

TEST_CASE("layers api: over the whole-layer size, slope/hillshade .tif and elevation/slope/hillshade .f32 are made "
          "band by band, cell for cell the whole map's, from the raw VRT and from the COG") {
  TempDir tmp;
  Hold hold;  // outlives the server whose jobs it holds
  ApiServerOptions o;
  o.defaultMap = false;
  o.backgroundCells = 0;       // stored raw first: the first files are read from the raw VRT
  o.wholeLayerCells = 10'000;  // the 613 × 389 map (238 457 cells) takes the streamed path
  ApiServer s(tmp.str("data"), o);
  hold.on(s);
  const auto up = s.post("/api/maps?name=bands&filename=bands.tif", testDem(tmp), "image/tiff");
  REQUIRE(up.status == 201);
  const std::string id = up.json()["id"];
  rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "the map's COG job");
  REQUIRE(s.get("/api/maps/" + id).json()["storage"]["elevation"] == "raw");
  const std::string base = "/api/maps/" + id + "/layers/";

  // Streamed from the raw VRT.
  auto slopeTif = s.get(base + "slope.tif");
  REQUIRE(slopeTif.status == 200);
  CHECK(slopeTif.headers["Content-Type"] == "image/tiff");
  auto slopeF32 = s.get(base + "slope.f32");
  REQUIRE(slopeF32.status == 200);
  CHECK(slopeF32.headers["X-Rows"] == std::to_string(kRows));
  CHECK(slopeF32.headers["X-Cols"] == std::to_string(kCols));
  CHECK(slopeF32.body.size() == 4u * kRows * kCols);
  checkError(s.get(base + "elevation.tif"), 503, "not_ready", "layer");  // the COG itself, not yet written

  hold.release = true;
  REQUIRE(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
  REQUIRE(s.get("/api/maps/" + id).json()["storage"]["elevation"] == "cog");
  // Streamed from the COG.
  std::map<std::string, std::string> streamed{{"slope.f32", slopeF32.body}};
  for (const std::string f : {"hillshade.tif", "elevation.f32", "hillshade.f32"}) {
    CAPTURE(f);
    const auto r = s.get(base + f);
    REQUIRE(r.status == 200);
    streamed[f] = r.body;
  }
  // The stored files, as before.
  CHECK(s.get(base + "elevation.tif").body == fileBytes(s.dir.mapDir(id) + "/dem.tif"));
  CHECK(s.get(base + "traversability.tif").status == 200);
  // What would load the whole map is refused, naming the size and what is made.
  for (const std::string f : {"slope.png", "elevation.png", "traversability.f32"}) {
    CAPTURE(f);
    const auto r = s.get(base + f);
    checkError(r, 413, "too_large", "layer");
    CHECK(r.body.find("613 x 389 cells") != std::string::npos);
    CHECK(r.body.find("10000 cells") != std::string::npos);
    CHECK(r.body.find("slope and hillshade as .tif and .f32") != std::string::npos);
  }
  CHECK(s.get(base + "slope.png?max=256").status == 200);  // overviews come from the pyramid

  // The streamed GeoTIFFs: tiled, compressed, georeferenced as the stored elevation, charged to
  // the map's disk budget.
  const std::string layers = s.dir.mapDir(id) + "/layers/";
  const Tif dem = readTif(s.dir.mapDir(id) + "/dem.tif");
  for (const std::string f : {"slope.tif", "hillshade.tif"}) {
    CAPTURE(f);
    const maps::PyramidInfo info = maps::pyramidInfo(layers + f);
    CHECK(info.compression == "DEFLATE");
    CHECK(info.blockWidth == 256);
    CHECK(info.blockHeight == 256);
    const Tif t = readTif(layers + f);
    CHECK(t.gt == dem.gt);
    CHECK(t.wkt == dem.wkt);
    CHECK(t.wkt.find("UTM zone 33N") != std::string::npos);
    CHECK(s.dir.budget().usedByMap(id) >= std::filesystem::file_size(layers + f));
  }
  CHECK(fileBytes(layers + "slope.tif") == slopeTif.body);

  // The same map's files made the whole-map way, by a catalog with the default size: the streamed
  // ones moved aside first, or it would find them in the layer cache.
  std::filesystem::create_directories(tmp.str("streamed"));
  for (const std::string f : {"slope.tif", "hillshade.tif", "slope.f32", "elevation.f32", "hillshade.f32"})
    std::filesystem::rename(layers + f, tmp.str("streamed/" + f));
  api::MapCatalog whole(s.db, s.dir);
  REQUIRE(whole.wholeLayerCells() == api::MapCatalog::kDefaultWholeLayerCells);
  for (const std::string f : {"slope.f32", "elevation.f32", "hillshade.f32"}) {
    CAPTURE(f);
    const std::string path = whole.layerFile(id, f.substr(0, f.find('.')), "f32", 0, "");
    CHECK(fileBytes(path) == streamed[f]);  // byte for byte, NaN where there is no data
  }
  const std::vector<float> heights = [&] {
    std::vector<float> v(std::size_t(kRows) * kCols);
    std::memcpy(v.data(), streamed["elevation.f32"].data(), v.size() * 4);
    return v;
  }();
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c)
      if (hole(r, c) != std::isnan(heights[std::size_t(r) * kCols + c])) FAIL("height of (" << r << ", " << c << ")");
  for (const std::string f : {"slope.tif", "hillshade.tif"}) {
    CAPTURE(f);
    const Tif a = readTif(tmp.str("streamed/" + f));
    const Tif b = readTif(whole.layerFile(id, f.substr(0, f.find('.')), "tif", 0, ""));
    REQUIRE(a.rows == kRows);
    REQUIRE(a.cols == kCols);
    CHECK(a.hasNodata == b.hasNodata);
    CHECK(a.nodata == b.nodata);
    CHECK(a.gt == b.gt);
    CHECK(a.wkt == b.wkt);
    REQUIRE(a.values.size() == b.values.size());
    CHECK(std::memcmp(a.values.data(), b.values.data(), a.values.size() * 4) == 0);
    // Not an empty comparison: nodata on the map's edges, around the holes and at the band
    // boundary rows beside them, values everywhere else.
    const auto at = [&](int r, int c) { return a.values[std::size_t(r) * kCols + c]; };
    int nodata = 0;
    for (float v : a.values) nodata += v == static_cast<float>(a.nodata);
    CHECK(nodata > 2 * kRows);
    CHECK(nodata < static_cast<int>(a.values.size()) / 4);
    for (int c = 0; c < kCols; ++c) {
      CHECK(at(0, c) == -9999.0f);
      CHECK(at(kRows - 1, c) == -9999.0f);
    }
    for (int r = 0; r < kRows; ++r) {
      CHECK(at(r, 0) == -9999.0f);
      CHECK(at(r, kCols - 1) == -9999.0f);
    }
    CHECK(at(249, 120) == -9999.0f);  // beside the hole, across the band boundary
    CHECK(at(262, 120) == -9999.0f);
    CHECK(at(254, 300) == -9999.0f);  // above the single cell of row 255
    CHECK(at(257, 200) == -9999.0f);  // below the single cell of row 256
    for (const auto& [r, c] : std::vector<std::pair<int, int>>{{1, 5}, {255, 20}, {256, 20}, {248, 120}, {263, 120},
                                                                {511, 30}, {512, 30}, {kRows - 2, 200}})
      CHECK(at(r, c) > 0.0f);
  }
}

TEST_CASE("layers api: a big map's .f32 over a quarter of the layer cache is refused, naming its size and the .tif") {
  TempDir tmp;
  ApiServerOptions o;
  o.defaultMap = false;
  o.wholeLayerCells = 10'000;
  ApiServer s(tmp.str("data"), o);
  const auto up = s.post("/api/maps?name=bands&filename=bands.tif", testDem(tmp), "image/tiff");
  REQUIRE(up.status == 201);
  const std::string id = up.json()["id"];
  // A layer cache of 3 MiB keeps 786 432 bytes for one raw export: the map's 953 828 do not fit.
  api::MapCatalog small(s.db, s.dir, api::MapCatalog::kDefaultMaxCells, 3ull << 20);
  small.setWholeLayerCells(10'000);
  try {
    small.layerFile(id, "slope", "f32", 0, "");
    FAIL("no 413");
  } catch (const http::ApiError& e) {
    CHECK(e.status() == 413);
    CHECK(e.field() == "layer");
    CHECK(std::string(e.what()).find("1.0 MB uncompressed, over the 0.8 MB") != std::string::npos);
    CHECK(std::string(e.what()).find("slope.tif") != std::string::npos);
  }
  CHECK(std::filesystem::exists(small.layerFile(id, "slope", "tif", 0, "")));
}
