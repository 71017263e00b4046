// The tile API over loopback (issue 24): the map's tile grid, PNG and float32 tiles, ETag and
// If-None-Match, the layer cache on disk, and hostile addresses answered 404 as JSON errors.
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <utility>
#include <vector>

#include <gdal.h>

#include "api_server.hpp"
#include "core/pdm/pdm.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/map_tiles.hpp"
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
  CHECK(cog.blockWidth == 128);
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

namespace {

// A PNG's width and height (its IHDR chunk).
std::pair<int, int> pngSize(const std::string& png) {
  auto be = [&](std::size_t at) {
    return (int(std::uint8_t(png[at])) << 24) | (int(std::uint8_t(png[at + 1])) << 16) |
           (int(std::uint8_t(png[at + 2])) << 8) | int(std::uint8_t(png[at + 3]));
  };
  REQUIRE(png.size() > 24);
  return {be(16), be(20)};
}

// The pdm tile z/x/y as the whole mass in memory draws it (what every pdm tile was before the
// mass pyramid): the mass discretised on the loaded map's grid and cells with data, its ramp
// over the whole mass.
// `components`: {x, y, sigma_x, sigma_y} each, unrotated, of weight 1.
std::string pdmTileInMemory(ApiServer& s, const std::string& map, const json& components, int z, int x, int y) {
  std::vector<pdm::Gaussian> gs;
  for (const auto& c : components) {
    pdm::Gaussian g;
    g.mean = {c["x"].get<double>(), c["y"].get<double>()};
    g.sigmaX = c["sigma_x"].get<double>();
    g.sigmaY = c["sigma_y"].get<double>();
    gs.push_back(g);
  }
  const auto m = s.maps.get(map);
  const Raster<float> mass = pdm::discretise(gs, m->dem.geometry(), m->valid);
  maps::TileSource src;
  src.pdm = &mass;
  src.range = maps::colourRange(maps::RenderLayer::Pdm, mass);
  const GridGeometry& g = m->dem.geometry();
  const auto window = maps::tileWindow(maps::tileGridOf(g.rows, g.cols), z, x, y);
  REQUIRE(window);
  const auto png = maps::encodePng(maps::renderTile(maps::RenderLayer::Pdm, src, *window), maps::PngColours::Smallest);
  return std::string(png.begin(), png.end());
}

}  // namespace

TEST_CASE("tiles api: pdm tiles come from the PDM's mass pyramid, one per version, at the native zoom byte for byte the in-memory tiles") {
  TempDir tmp;
  // A 300 × 200 map of 1 m cells with a hole of nodata (rows 50..79, columns 100..159): its cells
  // get no mass. Native zoom 1 (2 × 1 tiles), zmax 3.
  Raster<float> dem(GridGeometry{200, 300, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 200; ++r)
    for (int c = 0; c < 300; ++c)
      dem(r, c) = (r >= 50 && r < 80 && c >= 100 && c < 160) ? std::numeric_limits<float>::quiet_NaN()
                                                            : static_cast<float>(0.05 * c + 0.02 * r);
  maps::writeGeoTiff(tmp.str("hole.tif"), dem);
  std::ifstream in(tmp.str("hole.tif"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const json first = json::array({{{"x", 120}, {"y", 100}, {"sigma_x", 30}, {"sigma_y", 20}},
                                  {{"x", 250}, {"y", 40}, {"sigma_x", 8}, {"sigma_y", 8}}});
  std::string map, pdm;
  {
    ApiServer s(tmp.str("data"));
    const auto up = s.post("/api/maps?name=hole&filename=hole.tif", bytes, "image/tiff");
    REQUIRE(up.status == 201);
    map = up.json()["id"];
    const auto made = s.postJson("/api/maps/" + map + "/pdms", {{"name", "two"}, {"components", first}});
    REQUIRE(made.status == 201);
    pdm = made.json()["id"];
    // Made with the PDM; removed here (as an evicted cache file would be) so that the fresh
    // server below, with neither the map nor the PDM's mass in memory, makes it again from the
    // stored DEM's cells with data.
    const std::string massFile = s.dir.mapDir(map) + "/layers/pdm-" + pdm + "-mass.tif";
    REQUIRE(std::filesystem::exists(massFile));
    std::filesystem::remove(massFile);
  }
  ApiServer s(tmp.str("data"));
  const std::string base = "/api/maps/" + map + "/tiles/pdm/";
  std::vector<std::string> native;
  for (int x = 0; x < 2; ++x) {
    auto r = s.get(base + "1/" + std::to_string(x) + "/0.png?pdm=" + pdm);
    REQUIRE(r.status == 200);
    CHECK(r.headers["Cache-Control"] == "no-cache");
    native.push_back(r.body);
  }
  const std::string layers = s.dir.mapDir(map) + "/layers/";
  REQUIRE(std::filesystem::exists(layers + "pdm-" + pdm + "-mass.tif"));
  const maps::PyramidInfo info = maps::pyramidInfo(layers + "pdm-" + pdm + "-mass.tif");
  CHECK(info.layout == "COG");
  CHECK(info.rows == 200);
  CHECK(info.cols == 300);
  CHECK(info.overviews.size() == 1u);  // zoom 0
  for (int x = 0; x < 2; ++x) CHECK(native[x] == pdmTileInMemory(s, map, first, 1, x, 0));
  // Every zoom answers; the overview comes from the same pyramid, at the ladder's size.
  for (const std::string t : {"0/0/0", "2/2/1", "3/4/2"}) {
    CAPTURE(t);
    const auto r = s.get(base + t + ".png?pdm=" + pdm);
    CAPTURE(r.body);
    CHECK(r.status == 200);
  }
  const auto overview = s.get("/api/maps/" + map + "/layers/pdm.png?max=256&pdm=" + pdm);
  REQUIRE(overview.status == 200);
  CHECK(pngSize(overview.body).first == 256);

  // An edited PDM is a new version: new tiles, ETags and mass pyramid, drawn from its new mass.
  const json second = json::array({{{"x", 60}, {"y", 150}, {"sigma_x", 12}, {"sigma_y", 12}}});
  const auto edited = request(s.port(), "PUT", "/api/maps/" + map + "/pdms/" + pdm, json{{"components", second}}.dump(),
                              "application/json", {{"If-Match", "\"v1\""}});
  REQUIRE(edited.status == 200);
  auto v2 = s.get(base + "1/0/0.png?pdm=" + pdm);
  REQUIRE(v2.status == 200);
  CHECK(v2.headers["ETag"].find(pdm + "-v2-") != std::string::npos);
  CHECK(std::filesystem::exists(layers + "pdm-" + pdm + "-v2-mass.tif"));
  CHECK(v2.body != native[0]);
  CHECK(v2.body == pdmTileInMemory(s, map, second, 1, 0, 0));
  CHECK(s.get(base + "1/1/0.png?pdm=" + pdm).body == pdmTileInMemory(s, map, second, 1, 1, 0));
  // No request names version 1 any more: its tiles, overview and mass pyramid are gone, version
  // 2's stay. A deleted PDM leaves none of its files.
  auto filesOf = [&](const std::string& tag) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(layers)) {
      const std::string n = e.path().filename().string();
      for (const std::string& head : {"pdm-" + pdm, "t1-pdm-" + pdm})
        if (n.rfind(head, 0) == 0 && (tag.empty() ? n.find("-v") == std::string::npos : n.find(tag) != std::string::npos))
          names.push_back(n);
    }
    return names;
  };
  CHECK(filesOf("").empty());
  CHECK(filesOf("-v2-").size() >= 3u);  // two tiles and the mass pyramid
  const auto gone = request(s.port(), "DELETE", "/api/maps/" + map + "/pdms/" + pdm, "", "application/json", {});
  REQUIRE(gone.status == 200);
  CHECK(filesOf("-v2-").empty());
  CHECK(s.get("/api/maps/" + map + "/tiles/elevation/0/0/0.png").status == 200);  // the map's own tiles stay
}

TEST_CASE("layers api: a pyramid-stored map's overviews come from its pyramid, full-size files of a big map are "
          "its stored files, made band by band, or 413") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string id = s.defaultMap();  // 600 × 600, stored as its pyramid
  for (const char* layer : {"elevation", "hillshade", "slope", "traversability"}) {
    CAPTURE(layer);
    const auto r = s.get("/api/maps/" + id + "/layers/" + layer + ".png?max=256");
    REQUIRE(r.status == 200);
    CHECK(pngSize(r.body).first == 256);  // the map's 256 px and the legend below
    CHECK(pngSize(r.body).second > 256);
  }
  // The same map's DEM header made 5001 × 5001 cells (a sparse file: nothing to read): over the
  // 25 M cells whole-map layers are computed for, a full-size png or traversability.f32 is refused
  // from the header alone, naming the size; elevation.tif and traversability.tif are the stored
  // files (slope and hillshade files made band by band: test_layer_bands_api.cpp).
  maps::ensureGdal();
  const std::string dem = s.dir.mapDir(id) + "/dem.tif";
  std::filesystem::remove(dem);
  {
    const char* options[] = {"TILED=YES", "SPARSE_OK=YES", "COMPRESS=DEFLATE", nullptr};
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), dem.c_str(), 5001, 5001, 1, GDT_Float32,
                                 const_cast<char**>(options));
    REQUIRE(ds != nullptr);
    GDALClose(ds);
  }
  // A second catalog on the data dir: the first one keeps the 600² header it read.
  api::MapCatalog catalog(s.db, s.dir);
  for (const std::string f : {"hillshade.png", "slope.png", "traversability.f32", "traversability.png"}) {
    CAPTURE(f);
    try {
      catalog.layerFile(id, f.substr(0, f.find('.')), f.substr(f.find('.') + 1), 0, "");
      FAIL("no 413");
    } catch (const http::ApiError& e) {
      CHECK(e.status() == 413);
      CHECK(e.field() == "layer");
      CHECK(std::string(e.what()).find("5001 x 5001") != std::string::npos);
    }
  }
  CHECK(catalog.layerFile(id, "elevation", "tif", 0, "") == dem);
  CHECK(catalog.layerFile(id, "traversability", "tif", 0, "") == s.dir.mapDir(id) + "/classes.tif");
}

TEST_CASE("tiles api: a pdm tile whose PDM is edited or deleted as its mass pyramid is opened draws the current version, or is 404; never 500") {
  // The race is run exactly where it hurt: the tile has its version's mass pyramid file and has
  // not opened it when the edit or delete (forgetPdm) removes that file.
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();  // 600 × 600 cells: native zoom 2
  const json first = json::array({{{"x", 40}, {"y", 100}, {"sigma_x", 20}, {"sigma_y", 30}}});
  const json second = json::array({{{"x", 120}, {"y", 50}, {"sigma_x", 10}, {"sigma_y", 10}}});
  const auto made = s.postJson("/api/maps/" + map + "/pdms", {{"name", "p"}, {"components", first}});
  REQUIRE(made.status == 201);
  const std::string pdm = made.json()["id"];
  const std::string tile = "/api/maps/" + map + "/tiles/pdm/2/0/0.png?pdm=" + pdm;
  std::atomic<int> opened{0};
  std::atomic<bool> raced{false};
  std::function<bool()> race;  // on the work pool's thread: no assertion there
  s.maps.raceHooks.beforePdmPyramidRead = [&](const std::string& id) {
    if (id == pdm && opened++ == 0) raced = race();
  };
  SUBCASE("edited: the tile of the new version, named so") {
    race = [&] {
      pdm::Gaussian g;  // `second`'s one component
      g.mean = {120, 50};
      g.sigmaX = g.sigmaY = 10;
      store::PdmRecord out;
      return s.maps.changePdm(*s.db.getPdm(pdm), "p", std::vector<pdm::Gaussian>{g}, 1, "", out) == store::Cas::Done;
    };
    const auto r = s.get(tile);
    CHECK(raced.load());
    REQUIRE(r.status == 200);
    CHECK(r.headers.at("ETag").find(pdm + "-v2-") != std::string::npos);
    CHECK(r.body == pdmTileInMemory(s, map, second, 2, 0, 0));
    const auto again = s.get(tile);  // the file it left is the new version's
    CHECK(again.body == r.body);
    CHECK(again.headers.at("ETag") == r.headers.at("ETag"));
  }
  SUBCASE("deleted: 404 naming the PDM") {
    race = [&] {
      const bool gone = s.db.deletePdm(pdm);
      s.dir.remove(s.dir.pdmDir(pdm));
      s.maps.forgetPdm(map, pdm, std::nullopt);
      return gone;
    };
    const auto r = s.get(tile);
    CHECK(raced.load());
    checkError(r, 404, "not_found", "pdm");
  }
}
