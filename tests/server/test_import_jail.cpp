// Imports in a jail and georeferencing checked at import (issue 22), over loopback: a NaN pixel
// size is a 400 naming the geotransform's part (it used to be a 201 whose missions segfaulted the
// server); an import worker that dies of SIGSEGV or SIGKILL, or hangs past its deadline, or runs
// out of memory, is a 400/413 for that upload only and the server goes on; netCDF-4 is read.
#include <doctest/doctest.h>

#include <gdal.h>
#include <cpl_conv.h>
#include <gdal_utils.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/jail/import_jail.hpp"
#include "server/jail/worker_output.hpp"

using namespace rover;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A 40 × 40 GeoTIFF of synthetic terrain with geotransform `gt` (UTM 33N, or WGS 84), as bytes.
std::string tiffWith(const TempDir& t, const std::string& name, const std::array<double, 6>& gt, bool geographic = false) {
  maps::SyntheticTerrainParams p;
  p.size = 40;
  Raster<float> z = maps::generateTerrain(p).z;
  z.geo.valid = true;
  z.geo.geotransform = gt;
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, geographic ? 4326 : 32633);
  char* wkt = nullptr;
  OSRExportToWkt(srs, &wkt);
  z.geo.crsWkt = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  const std::string path = t.str(name);
  maps::writeGeoTiff(path, z);
  return readBytes(path);
}

std::string goodTiff(const TempDir& t) { return tiffWith(t, "good.tif", {500000, 0.25, 0, 4100010, 0, -0.25}); }

test::HttpResult upload(test::ApiServer& s, const std::string& filename, const std::string& bytes) {
  return request(s.port(), "POST", "/api/maps?filename=" + filename, bytes, "application/octet-stream");
}

std::string message(const test::HttpResult& r) { return r.json()["error"].value("message", ""); }

// The server answers and still imports a good file.
void checkStillServing(test::ApiServer& s, const TempDir& t) {
  CHECK(s.get("/api/health").status == 200);
  auto r = upload(s, "good.tif", goodTiff(t));
  CHECK_MESSAGE(r.status == 201, r.body);
}

// A worker that is not GDAL but ends as a broken GDAL would: /bin/sh running `script` (the jail
// appends IN and OUT, which become $1 and $2).
jail::JailConfig shellWorker(test::ApiServer& s, const std::string& script, double deadline = 30) {
  jail::JailConfig c = s.maps.importJail();
  c.worker = {"/bin/sh", "-c", script, "worker"};
  c.limits.deadlineSeconds = deadline;
  return c;
}

}  // namespace

TEST_CASE("import jail: NaN, 1e-300, 1e300 and infinite pixel sizes are a 400 naming the geotransform part") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  const std::size_t before = s.get("/api/maps").json().size();
  // gdal_edit.py -a_ullr 0 nan 100 0 n.tif: origin_y and pixel_height NaN (issue 22: 201, then a
  // segfault in planning::checkMissionStarts on a team-search mission).
  auto r = upload(s, "n.tif", tiffWith(t, "n.tif", {0, 2.5, 0, NAN, 0, NAN}));
  test::checkError(r, 400, "invalid_dem", "geotransform.pixel_height");
  CHECK(message(r).rfind("n.tif: the geotransform's pixel_height is nan", 0) == 0);
  test::checkError(upload(s, "tiny.tif", tiffWith(t, "tiny.tif", {500000, 1e-300, 0, 4100000, 0, -1})), 400, "invalid_dem",
                   "geotransform.pixel_width");
  test::checkError(upload(s, "huge.tif", tiffWith(t, "huge.tif", {500000, 1, 0, 4100000, 0, -1e300})), 400, "invalid_dem",
                   "geotransform.pixel_height");
  test::checkError(upload(s, "inf.tif", tiffWith(t, "inf.tif", {500000, INFINITY, 0, 4100000, 0, -1})), 400, "invalid_dem",
                   "geotransform.pixel_width");
  CHECK(s.get("/api/maps").json().size() == before);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("import jail: latitudes over 90 and longitudes of 5000 degrees are a 400 naming the geotransform part") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  auto r = upload(s, "lat.tif", tiffWith(t, "lat.tif", {10, 1e-4, 0, 95, 0, -1e-4}, true));
  test::checkError(r, 400, "invalid_dem", "geotransform.origin_y");
  CHECK(message(r).find("latitude of 95°") != std::string::npos);
  test::checkError(upload(s, "lon.tif", tiffWith(t, "lon.tif", {5000, 1e-4, 0, 10, 0, -1e-4}, true)), 400, "invalid_dem",
                   "geotransform.origin_x");
  test::checkError(upload(s, "lonw.tif", tiffWith(t, "lonw.tif", {-5000, 1e-4, 0, 10, 0, -1e-4}, true)), 400,
                   "invalid_dem", "geotransform.origin_x");
  // The same ground at a sane place is a map.
  r = upload(s, "ok.tif", tiffWith(t, "ok.tif", {10, 1e-5, 0, 45, 0, -1e-5}, true));
  CHECK_MESSAGE(r.status == 201, r.body);
}

TEST_CASE("import jail: a PDM raster with a NaN geotransform is a 400 naming the part") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  auto map = upload(s, "good.tif", goodTiff(t));
  REQUIRE(map.status == 201);
  const std::string id = map.json()["id"];
  auto r = request(s.port(), "POST", "/api/maps/" + id + "/pdms?filename=w.tif",
                   tiffWith(t, "w.tif", {500000, NAN, 0, 4100010, 0, -0.25}), "application/octet-stream");
  test::checkError(r, 400, "invalid_pdm", "geotransform.pixel_width");
  CHECK(message(r).rfind("PDM raster", 0) == 0);
}

TEST_CASE("import jail: a worker killed by SIGSEGV or SIGKILL is a 400 with the signal and the server goes on") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  const jail::JailConfig normal = s.maps.importJail();
  const std::size_t before = s.get("/api/maps").json().size();
  for (const auto& kill : {std::pair<std::string, int>{"SEGV", 11}, {"KILL", 9}}) {
    const std::string& signal = kill.first;  // not a structured binding: clang 14 cannot capture one
    const int number = kill.second;
    CAPTURE(signal);
    s.maps.setImportJail(shellWorker(s, "kill -" + signal + " $$"));
    auto r = upload(s, "crash.tif", goodTiff(t));
    test::checkError(r, 400, "import_crashed", "file");
    CHECK(message(r).find("the importer crashed (signal " + std::to_string(number) + ")") != std::string::npos);
    CHECK(s.get("/api/health").status == 200);
  }
  // A PDM raster's worker too.
  s.maps.setImportJail(shellWorker(s, "kill -SEGV $$"));
  auto r = request(s.port(), "POST", "/api/maps/" + s.defaultMap() + "/pdms?filename=w.tif", goodTiff(t),
                   "application/octet-stream");
  test::checkError(r, 400, "import_crashed", "file");
  s.maps.setImportJail(normal);
  checkStillServing(s, t);
  CHECK(s.get("/api/maps").json().size() == before + 1);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("import jail: a worker that hangs is killed at its deadline and the upload is a 400") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  const jail::JailConfig normal = s.maps.importJail();
  // The deadline (1 s) is what ends this worker: its sleep would last 10 minutes.
  s.maps.setImportJail(shellWorker(s, "sleep 600", 1));
  auto r = upload(s, "hang.tif", goodTiff(t));
  test::checkError(r, 400, "import_timeout", "file");
  CHECK(message(r).find("did not finish") != std::string::npos);
  s.maps.setImportJail(normal);
  checkStillServing(s, t);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

// Sanitizer builds set no RLIMIT_AS (jail::kAddressSpaceLimited): the Release suite checks this one.
TEST_CASE("import jail: a file that needs more memory than the worker may use is a 413" *
          doctest::skip(!jail::kAddressSpaceLimited)) {
  TempDir t;
  test::ApiServer s(t.str("data"));
  // 3000 x 3000 cells resampled to 6000 x 6000: a 144 MB float32 grid, with an address space of
  // 256 MiB for a worker that needs about 200 MiB to start (measured with prlimit --as).
  maps::SyntheticTerrainParams p;
  p.size = 3000;
  const std::string path = t.str("big.tif");
  maps::writeGeoTiff(path, maps::generateTerrain(p).z);
  const jail::JailConfig normal = s.maps.importJail();
  jail::JailConfig c = normal;
  c.limits.memoryBytes = 256ull << 20;
  s.maps.setImportJail(c);
  auto r = request(s.port(), "POST", "/api/maps?filename=big.tif&cell=0.125", readBytes(path), "application/octet-stream");
  CHECK_MESSAGE(r.status == 413, r.body);
  CHECK(r.json()["error"].value("code", "") == "too_large");
  s.maps.setImportJail(normal);
  checkStillServing(s, t);
}

TEST_CASE("import jail: a netCDF-4 (HDF5) upload is read when the worker runs under bubblewrap") {
  TempDir t;
  test::ApiServer s(t.str("data"));
  const std::string tif = t.str("src.tif");
  {
    std::ofstream(tif, std::ios::binary) << goodTiff(t);
  }
  // gdal_translate -of netCDF -co FORMAT=NC4 src.tif dem.nc
  const std::string nc = t.str("dem.nc");
  GDALDatasetH src = GDALOpen(tif.c_str(), GA_ReadOnly);
  REQUIRE(src);
  const char* argv[] = {"-of", "netCDF", "-co", "FORMAT=NC4", nullptr};
  GDALTranslateOptions* o = GDALTranslateOptionsNew(const_cast<char**>(argv), nullptr);
  GDALDatasetH out = GDALTranslate(nc.c_str(), src, o, nullptr);
  GDALTranslateOptionsFree(o);
  GDALClose(src);
  REQUIRE(out);
  GDALClose(out);
  const std::string bytes = readBytes(nc);
  REQUIRE(bytes.substr(1, 3) == "HDF");  // netCDF-4 is HDF5
  auto r = upload(s, "dem.nc", bytes);
  if (jail::isolation() == jail::Isolation::Bubblewrap) {
    REQUIRE_MESSAGE(r.status == 201, r.body);
    CHECK(r.json()["driver"] == "netCDF");
    CHECK(r.json()["rows"] == 40);
  } else {
    MESSAGE("no bubblewrap here: netCDF-4 stays refused (" << jail::isolationInWords(jail::isolation()) << ")");
    test::checkError(r, 400, "refused_file", "file");
  }
}

TEST_CASE("import jail: the server's figures of the worker's grid (NaN count, lowest, highest) and its infinities") {
  // rover::jail::readWorkerGrid checks every value four at a time: the lowest, highest, NaNs and
  // an infinity in the vector part and in the tail a row of 4k + 3 cells leaves.
  TempDir t;
  const std::string out = t.path.string();
  for (const int at : {0, 5, 41 * 23 - 1, 17 * 23 + 22}) {
    CAPTURE(at);
    maps::LoadedDem d;
    d.dem.z = Raster<float>(GridGeometry{41, 23, 1.0, 1.0}, 0.0f);
    for (int i = 0; i < 41 * 23; ++i) d.dem.z.values.data()[i] = 100.0f + static_cast<float>(i % 37);
    float* v = d.dem.z.values.data();
    v[at] = -7.5f;                       // the lowest
    v[(at + 11) % (41 * 23)] = 512.25f;  // the highest
    for (int i = 3; i < 41 * 23; i += 97) v[(at + i) % (41 * 23)] = std::numeric_limits<float>::quiet_NaN();
    std::int64_t nans = 0;
    for (int i = 0; i < 41 * 23; ++i) nans += std::isnan(v[i]) ? 1 : 0;
    jail::writeWorkerResult(out, d, "x.tif");
    const jail::WorkerResult r = jail::readWorkerResult(out, 1 << 20);
    CHECK(r.dem.info.minHeight == -7.5);
    CHECK(r.dem.info.maxHeight == 512.25);
    CHECK(r.dem.info.nodataCells == nans);
    for (const float inf : {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
      v[at] = inf;
      jail::writeWorkerResult(out, d, "x.tif");
      CHECK_THROWS_WITH(jail::readWorkerResult(out, 1 << 20), doctest::Contains("infinite"));
    }
  }
}
