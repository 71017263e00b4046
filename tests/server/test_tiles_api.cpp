// The tile API over loopback (issue 24): the map's tile grid, PNG and float32 tiles, ETag and
// If-None-Match, the layer cache on disk, and hostile addresses answered 404 as JSON errors.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include <gdal.h>

#include "api_server.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/gdal_env.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

std::vector<float> floats(const std::string& bytes) {
  std::vector<float> v(bytes.size() / 4);
  std::memcpy(v.data(), bytes.data(), v.size() * 4);
  return v;
}

}  // namespace

TEST_CASE("tiles api: grid metadata, tiles equal to the whole layer's values, ETag and 304") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string id = s.defaultMap();
  // The default map: 600 × 600 cells of 0.25 m → native zoom 2 (1024 px), zmax 4.
  const json tiles = s.get("/api/maps/" + id).json()["tiles"];
  CHECK(tiles["tile_size"] == 256);
  CHECK(tiles["zmax"] == 4);
  CHECK(tiles["native_zoom"] == 2);
  REQUIRE(tiles["resolutions"].size() == 5);
  CHECK(tiles["resolutions"][0].get<double>() == doctest::Approx(1.0));
  CHECK(tiles["resolutions"][2].get<double>() == doctest::Approx(0.25));
  CHECK(tiles["resolutions"][4].get<double>() == doctest::Approx(0.0625));
  REQUIRE(tiles["extent"].size() == 4);
  for (int i = 0; i < 4; ++i) CHECK(tiles["extent"][i].get<double>() == doctest::Approx(i < 2 ? 0.0 : 150.0));
  CHECK(tiles["origin"][1].get<double>() == doctest::Approx(150.0));
  CHECK(tiles["tile_counts"][2] == json({3, 3}));

  const std::string base = "/api/maps/" + id + "/tiles/";
  auto png = s.get(base + "elevation/2/1/1.png");
  REQUIRE(png.status == 200);
  CHECK(png.headers["Content-Type"] == "image/png");
  CHECK(png.body.substr(1, 3) == "PNG");
  CHECK(png.headers["Cache-Control"] == "public, max-age=31536000, immutable");
  const std::string etag = png.headers["ETag"];
  CHECK(etag.find(id) != std::string::npos);
  // The fresh tile was answered from memory; the next request is answered from its cache file:
  // the same bytes and headers.
  auto warm = s.get(base + "elevation/2/1/1.png");
  CHECK(warm.status == 200);
  CHECK(warm.body == png.body);
  CHECK(warm.headers["ETag"] == etag);
  CHECK(warm.headers["Content-Type"] == "image/png");
  CHECK(warm.headers["Cache-Control"] == png.headers["Cache-Control"]);
  // The same tile again with its ETag: 304, no body; another tile's ETag does not match.
  auto again = request(s.port(), "GET", base + "elevation/2/1/1.png", "", "", {{"If-None-Match", etag}});
  CHECK(again.status == 304);
  CHECK(again.body.empty());
  CHECK(again.headers["ETag"] == etag);
  auto other = request(s.port(), "GET", base + "elevation/2/1/0.png", "", "", {{"If-None-Match", etag}});
  CHECK(other.status == 200);
  CHECK(other.headers["ETag"] != etag);
  // The tile is a file of the layer cache, in the map's layers folder.
  bool onDisk = false;
  for (const auto& f : std::filesystem::directory_iterator(s.dir.mapDir(id) + "/layers"))
    onDisk |= f.path().filename() == "t1-elevation-2-1-1.png";
  CHECK(onDisk);

  // Float tiles: the cells of the whole layer, NaN beyond the map (the last tile holds 600 − 512
  // = 88 rows and columns).
  const auto whole = floats(s.get("/api/maps/" + id + "/layers/slope.f32").body);
  REQUIRE(whole.size() == 600u * 600u);
  for (auto [x, y] : {std::pair{0, 0}, std::pair{1, 1}, std::pair{2, 2}, std::pair{2, 0}}) {
    auto r = s.get(base + "slope/2/" + std::to_string(x) + "/" + std::to_string(y) + ".f32");
    REQUIRE(r.status == 200);
    CHECK(r.headers["X-Rows"] == "256");
    const auto tile = floats(r.body);
    REQUIRE(tile.size() == 256u * 256u);
    for (int py = 0; py < 256; ++py)
      for (int px = 0; px < 256; ++px) {
        const int row = y * 256 + py, col = x * 256 + px;
        const float v = tile[py * 256 + px];
        if (row >= 600 || col >= 600) REQUIRE(std::isnan(v));
        else REQUIRE(((std::isnan(v) && std::isnan(whole[row * 600 + col])) || v == whole[row * 600 + col]));
      }
  }
  // Every layer renders at every zoom; a pdm tile names its PDM.
  for (const char* layer : {"hillshade", "slope", "traversability"})
    for (int z = 0; z <= 4; ++z) CHECK(s.get(base + layer + "/" + std::to_string(z) + "/0/0.png").status == 200);
  auto pdm = s.postJson("/api/maps/" + id + "/pdms", {{"random", 3}, {"seed", 2}});
  REQUIRE(pdm.status == 201);
  const std::string pdmId = pdm.json()["id"];
  CHECK(s.get(base + "pdm/1/0/0.png?pdm=" + pdmId).status == 200);
  checkError(s.get(base + "pdm/1/0/0.png"), 400, "pdm");
  checkError(s.get(base + "pdm/1/0/0.png?pdm=nope"), 404, "pdm");
}

TEST_CASE("tiles api: hostile tile addresses are 404 JSON errors, never 500") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string base = "/api/maps/" + s.defaultMap() + "/tiles/";
  for (const char* bad : {"elevation/5/0/0.png", "elevation/2/3/0.png", "elevation/2/0/3.png", "elevation/0/1/0.png",
                          "elevation/-1/0/0.png", "elevation/0/-1/0.png", "elevation/0/0/-1.png",
                          "elevation/99999999999999999999/0/0.png", "elevation/2/99999999999/0.png",
                          "elevation/2/0/999999999.png", "elevation/2/0/1e3.png", "elevation/x/0/0.png",
                          "elevation/2/0x1/0.png", "elevation/%20/0/0.png", "elevation/2/0/0", "elevation/2/0/.png",
                          "elevation/2/0/0.jpg", "elevation/2/0/0.png.png", "hillshade/0/0/0.f32",
                          "traversability/0/0/0.f32", "nope/0/0/0.png", "../0/0/0.png"}) {
    const std::string address = bad;
    CAPTURE(address);
    const auto r = s.get(base + bad);
    // The HTTP layer refuses some targets (dot segments, a space) before any route: 400 on "path".
    if (r.status == 400) {
      CHECK(r.json()["error"]["field"] == "path");
      continue;
    }
    CHECK(r.status == 404);
    CHECK(r.json()["error"]["code"] == "not_found");
  }
  checkError(s.get("/api/maps/nope/tiles/elevation/0/0/0.png"), 404, "id");
}

TEST_CASE("tiles api: a map is stored as its pyramid; a map stored before (no overviews, no class pyramid) gives the same native tiles") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string a = s.defaultMap();
  const json map = s.get("/api/maps/" + a).json();
  CHECK(map["storage"]["elevation"] == "cog");
  CHECK(map["storage"]["overviews"] == 2);  // 600 × 600: zooms 1 and 0 below the native zoom 2
  REQUIRE(map["colour_range"].size() == 2);
  const maps::PyramidInfo cog = maps::pyramidInfo(s.dir.mapDir(a) + "/dem.tif");
  CHECK(cog.layout == "COG");
  CHECK(cog.blockWidth == 256);
  CHECK(cog.overviews.size() == 2u);
  // The same cells uploaded again as a plain GeoTIFF (the elevation export), then turned back into
  // a map as stored before the pyramid: the old writer's dem.tif, no classes.tif.
  const auto exported = s.get("/api/maps/" + a + "/layers/elevation.tif");
  REQUIRE(exported.status == 200);
  const auto up = s.post("/api/maps?name=old&filename=dem.tif", exported.body, "image/tiff");
  REQUIRE(up.status == 201);
  const std::string b = up.json()["id"];
  const std::string bDir = s.dir.mapDir(b);
  std::filesystem::remove(bDir + "/classes.tif");
  {
    std::ofstream out(bDir + "/dem.tif", std::ios::binary | std::ios::trunc);
    out << exported.body;  // maps::writeGeoTiff's file: tiled, nodata -9999, no overviews
  }
  REQUIRE(maps::pyramidInfo(bDir + "/dem.tif").overviews.empty());
  for (const char* tile : {"elevation/2/0/0.png", "hillshade/2/1/1.png", "slope/2/2/2.png", "traversability/2/1/0.png",
                           "slope/3/2/1.png", "elevation/2/2/1.f32", "slope/2/1/2.f32"}) {
    CAPTURE(tile);
    const auto fromPyramid = s.get("/api/maps/" + a + "/tiles/" + tile);
    const auto fromOld = s.get("/api/maps/" + b + "/tiles/" + tile);
    REQUIRE(fromPyramid.status == 200);
    REQUIRE(fromOld.status == 200);
    CHECK(fromPyramid.body == fromOld.body);
  }
  // Below the native zoom both answer (the old map from the whole map in memory, as before).
  for (const std::string& id : {a, b})
    for (const char* tile : {"elevation/0/0/0.png", "traversability/1/1/1.png", "slope/0/0/0.f32"})
      CHECK(s.get("/api/maps/" + id + "/tiles/" + tile).status == 200);
}

TEST_CASE("tiles api: the cell budget is 300 M cells, checked from the file's header before a cell is read") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  CHECK(api::MapCatalog::kDefaultMaxCells == 300'000'000);
  // A sparse tiled GeoTIFF of 17 321 × 17 321 cells (300 017 041, just over): a few hundred KB on
  // disk, refused from its header alone (nothing of 1.2 GB is allocated).
  maps::ensureGdal();
  const std::string path = tmp.str("big.tif");
  {
    const char* options[] = {"TILED=YES", "SPARSE_OK=YES", "COMPRESS=DEFLATE", nullptr};
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 17321, 17321, 1, GDT_Float32,
                                 const_cast<char**>(options));
    REQUIRE(ds != nullptr);
    GDALClose(ds);
  }
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  REQUIRE(bytes.size() < (4u << 20));
  const auto r = s.post("/api/maps?name=big&filename=big.tif", bytes, "image/tiff");
  checkError(r, 400, "too_large", "file");
  CHECK(r.json()["error"]["message"].get<std::string>().find("300000000") != std::string::npos);
}
