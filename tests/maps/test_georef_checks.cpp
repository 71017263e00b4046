// Georeferencing checked at import (issue 22): a NaN, zero, 1e-300, 1e300 or infinite pixel size,
// a latitude past the pole or a longitude of ±5000° is refused with the geotransform's part named,
// by loadDem (the CLI, uploads in the import worker) and by maps::georefProblem itself.
#include <doctest/doctest.h>

#include <gdal.h>
#include <ogr_srs_api.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

struct Scratch {
  fs::path path = fs::temp_directory_path() / ("roverplan-georef-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(path); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& n) const { return (path / n).string(); }
};

// A 10 × 12 Float32 GeoTIFF with geotransform `gt`, geographic (WGS 84) or UTM 33N, written
// through GDAL as gdal_edit.py would leave it.
std::string tiffWith(const Scratch& s, const std::string& name, const std::array<double, 6>& gt, bool geographic) {
  maps::ensureGdal();
  const std::string path = s.file(name);
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 12, 10, 1, GDT_Float32, nullptr);
  REQUIRE(ds);
  double t[6];
  std::copy(gt.begin(), gt.end(), t);
  GDALSetGeoTransform(ds, t);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, geographic ? 4326 : 32633);
  GDALSetSpatialRef(ds, srs);
  OSRDestroySpatialReference(srs);
  std::vector<float> z(120);
  for (int i = 0; i < 120; ++i) z[i] = 0.01f * i;
  CHECK(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 12, 10, z.data(), 12, 10, GDT_Float32, 0, 0) == CE_None);
  GDALClose(ds);
  return path;
}

// The field loadDem refuses `path` with ("" when it loads).
std::string refusedField(const std::string& path, std::string* message = nullptr) {
  try {
    maps::loadDem(path);
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.field();
  }
  return "";
}

}  // namespace

TEST_CASE("georef: NaN, zero, 1e-300, 1e300 and infinite pixel sizes are refused naming the part") {
  Scratch s;
  // gdal_edit.py -a_ullr 0 nan 100 0: the origin's Y and the pixel height are NaN; the pixel
  // size is named first.
  CHECK(refusedField(tiffWith(s, "nan.tif", {0, 100.0 / 12, 0, NAN, 0, NAN}, false)) == "geotransform.pixel_height");
  CHECK(refusedField(tiffWith(s, "nanw.tif", {500000, NAN, 0, 4100000, 0, -1}, false)) == "geotransform.pixel_width");
  CHECK(refusedField(tiffWith(s, "tiny.tif", {500000, 1e-300, 0, 4100000, 0, -1}, false)) == "geotransform.pixel_width");
  CHECK(refusedField(tiffWith(s, "huge.tif", {500000, 1e300, 0, 4100000, 0, -1}, false)) == "geotransform.pixel_width");
  CHECK(refusedField(tiffWith(s, "hugeh.tif", {500000, 1, 0, 4100000, 0, -1e300}, false)) == "geotransform.pixel_height");
  CHECK(refusedField(tiffWith(s, "inf.tif", {500000, INFINITY, 0, 4100000, 0, -1}, false)) == "geotransform.pixel_width");
  std::string message;
  CHECK(refusedField(tiffWith(s, "mm.tif", {500000, 1e-4, 0, 4100000, 0, -1e-4}, false), &message) ==
        "geotransform.pixel_width");
  CHECK(message.find("0.0001 m is outside the accepted range of 0.001 to 100000 m") != std::string::npos);
  // The edges of the range are accepted: 1 mm and 100 km pixels.
  CHECK(refusedField(tiffWith(s, "1mm.tif", {500000, 1e-3, 0, 4100000, 0, -1e-3}, false)) == "");
  CHECK(refusedField(tiffWith(s, "100km.tif", {0, 1e5, 0, 4e6, 0, -1e5}, false)) == "");
}

TEST_CASE("georef: latitudes past the poles and longitudes of 5000 degrees are refused") {
  Scratch s;
  std::string message;
  CHECK(refusedField(tiffWith(s, "lat95.tif", {10, 0.01, 0, 95, 0, -0.01}, true), &message) == "geotransform.origin_y");
  CHECK(message.find("latitude of 95° is outside [-90, 90]°") != std::string::npos);
  // An origin inside, a raster that runs past the south pole: the pixel height carried it there.
  CHECK(refusedField(tiffWith(s, "south.tif", {10, 0.01, 0, -89, 0, -1}, true)) == "geotransform.pixel_height");
  CHECK(refusedField(tiffWith(s, "lon5000.tif", {5000, 0.01, 0, 10, 0, -0.01}, true)) == "geotransform.origin_x");
  CHECK(refusedField(tiffWith(s, "lonm5000.tif", {-5000, 0.01, 0, 10, 0, -0.01}, true)) == "geotransform.origin_x");
  // A 1 m pixel in degrees is 9e-6°; a 2° pixel on Earth is 222 km: over 100 km.
  CHECK(refusedField(tiffWith(s, "deg2.tif", {0, 2, 0, 40, 0, -2}, true)) == "geotransform.pixel_width");
  // Real maps: 0..360 longitudes, a pole-to-pole strip, the Luxembourg SRTM pixel.
  CHECK(refusedField(tiffWith(s, "east.tif", {350, 0.5, 0, 5, 0, -0.5}, true)) == "");
  CHECK(refusedField(tiffWith(s, "srtm.tif", {5.74, 0.00833, 0, 50.19, 0, -0.00833}, true)) == "");
  // Projected coordinates beyond 100 000 km are no place on any body.
  CHECK(refusedField(tiffWith(s, "far.tif", {1e12, 1, 0, 0, 0, -1}, false)) == "geotransform.origin_x");
}

TEST_CASE("georef: georefProblem checks rotated geotransforms by their pixel sides and corners") {
  maps::CrsUnits metres;
  // 30° rotated 2 m pixels: sides of 2 m, accepted.
  const double c = 2 * std::cos(M_PI / 6), sn = 2 * std::sin(M_PI / 6);
  CHECK_FALSE(maps::georefProblem({1000, c, sn, 5000, sn, -c}, 100, 100, metres));
  // Parallel axes: no area.
  auto p = maps::georefProblem({0, 1, 1, 0, 1, 1}, 10, 10, metres);
  REQUIRE(p);
  CHECK(p->field == "geotransform");
  // A zero pixel height says so.
  p = maps::georefProblem({0, 1, 0, 0, 0, 0}, 10, 10, metres);
  REQUIRE(p);
  CHECK(p->field == "geotransform.pixel_height");
  CHECK(p->reason == "the pixel height is zero");
  // A geographic CRS in degrees on Mars' sphere: 1° is 59.3 km (accepted), 2° 118.5 km (refused).
  maps::CrsUnits mars;
  mars.geographic = true;
  mars.degreesPerUnit = 1;
  mars.metresPerUnit = 3396190.0 * M_PI / 180;
  CHECK_FALSE(maps::georefProblem({-180, 1, 0, 90, 0, -1}, 180, 360, mars));
  CHECK(maps::georefProblem({-180, 2, 0, 90, 0, -2}, 90, 180, mars));
}

TEST_CASE("georef: checkGeoreference throws rover::Error naming the part, and skips rasters without one") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {0, NAN, 0, 0, 0, -1};
  CHECK_THROWS_WITH_AS(maps::checkGeoreference(geo, 4, 4), "the geotransform's pixel_width is nan, not a finite number",
                       Error);
  try {
    maps::checkGeoreference(geo, 4, 4);
  } catch (const Error& e) {
    CHECK(e.field() == "geotransform.pixel_width");
    CHECK(e.code() == ErrorCode::InvalidInput);
  }
  geo.valid = false;
  CHECK_NOTHROW(maps::checkGeoreference(geo, 4, 4));
}
