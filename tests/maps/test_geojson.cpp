#include <cpl_conv.h>
#include <cpl_vsi.h>
#include <doctest/doctest.h>
#include <gdal.h>
#include <unistd.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"
#include "maps/geojson.hpp"
#include "maps/georef.hpp"

using rover::GeoReference;
using rover::GridGeometry;
using rover::Metric;
using rover::TargetStatus;
using rover::Track;
using namespace rover::maps;

namespace {

void checkNear(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double tol = 1e-6) {
  CHECK(std::abs(a.x() - b.x()) <= tol * std::max(1.0, std::abs(b.x())));
  CHECK(std::abs(a.y() - b.y()) <= tol * std::max(1.0, std::abs(b.y())));
}

std::string wktFrom(const char* userInput) {
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  REQUIRE(OSRSetFromUserInput(srs, userInput) == OGRERR_NONE);
  char* wkt = nullptr;
  REQUIRE(OSRExportToWkt(srs, &wkt) == OGRERR_NONE);
  std::string out = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  return out;
}

// The GeoJSON text parsed back with OGR (through a /vsimem/ copy).
struct Parsed {
  GDALDatasetH ds = nullptr;
  OGRLayerH layer = nullptr;
  std::string path;
  explicit Parsed(const std::string& json) {
    ensureGdal();
    static int counter = 0;
    path = "/vsimem/test_geojson_" + std::to_string(counter++) + ".geojson";
    VSILFILE* f = VSIFOpenL(path.c_str(), "wb");
    REQUIRE(f != nullptr);
    REQUIRE(VSIFWriteL(json.data(), 1, json.size(), f) == json.size());
    VSIFCloseL(f);
    const char* drivers[] = {"GeoJSON", nullptr};
    ds = GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, drivers, nullptr, nullptr);
    REQUIRE(ds != nullptr);
    REQUIRE(GDALDatasetGetLayerCount(ds) == 1);
    layer = GDALDatasetGetLayer(ds, 0);
  }
  ~Parsed() {
    if (ds) GDALClose(ds);
    VSIUnlink(path.c_str());
  }
  Parsed(const Parsed&) = delete;
  Parsed& operator=(const Parsed&) = delete;
};

const GridGeometry kGrid{100, 50, 2.0, 2.0};  // 100 rows × 50 cols of 2 m: 100 m × 200 m

}  // namespace

TEST_CASE("georef: without a georeference the CRS is the local frame") {
  const GeoReference none;
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0, 0), Eigen::Vector2d(12.5, 190.25),
                                  Eigen::Vector2d(100, 200), Eigen::Vector2d(-3, 250)}) {
    checkNear(localToCrs(kGrid, none, p), p, 1e-12);
    checkNear(crsToLocal(kGrid, none, p), p, 1e-12);
  }
}

TEST_CASE("georef: a north-up geotransform maps the lower-left corner and cell centres") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {500000, 2, 0, 4000000, 0, -2};  // top-left corner at (500000, 4000000)
  // The local origin is the lower-left corner: 100 rows × 2 m below the top.
  checkNear(localToCrs(kGrid, geo, {0, 0}), {500000, 3999800});
  checkNear(localToCrs(kGrid, geo, {100, 200}), {500100, 4000000});
  // The centre of cell (row 0, col 0) is 1 m east and 199 m north of the origin.
  checkNear(localToCrs(kGrid, geo, {1, 199}), {500001, 3999999});
  checkNear(localToCrs(kGrid, geo, {10, 20}), {500010, 3999820});
  checkNear(crsToLocal(kGrid, geo, {500010, 3999820}), {10, 20});

  // A pixel size that differs from the nominal cell size (e.g. degrees): the local frame is the
  // pixel grid scaled by the cell size.
  GeoReference deg;
  deg.valid = true;
  deg.geotransform = {137.0, 0.001, 0, -4.5, 0, -0.001};
  const Eigen::Vector2d p(30, 50);  // col 15, row 75
  checkNear(localToCrs(kGrid, deg, p), {137.015, -4.575}, 1e-12);
  checkNear(crsToLocal(kGrid, deg, localToCrs(kGrid, deg, p)), p, 1e-9);
}

TEST_CASE("georef: rotated geotransforms round-trip through the 2x2 inverse") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {1000, 1.6, 1.2, 2000, 1.2, -1.6};  // rotated and scaled pixels
  const Eigen::Vector2d p(31, 47);
  const double col = 31 / 2.0, row = 100 - 47 / 2.0;
  checkNear(localToCrs(kGrid, geo, p), {1000 + col * 1.6 + row * 1.2, 2000 + col * 1.2 - row * 1.6});
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(0, 0), Eigen::Vector2d(99.5, 0.5),
                                  Eigen::Vector2d(3, 177), Eigen::Vector2d(-20, 250)})
    checkNear(crsToLocal(kGrid, geo, localToCrs(kGrid, geo, q)), q, 1e-9);

  GeoReference singular;
  singular.valid = true;
  singular.geotransform = {0, 1, 2, 0, 2, 4};
  try {
    crsToLocal(kGrid, singular, {1, 1});
    FAIL("no error for a singular geotransform");
  } catch (const rover::Error& e) {
    CHECK(e.code() == rover::ErrorCode::InvalidInput);
    CHECK(e.field() == "geotransform");
  }
}

TEST_CASE("geojson: one feature per track with CRS coordinates and metric properties") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {500000, 2, 0, 4000000, 0, -2};
  geo.crsWkt = wktFrom("EPSG:32633");

  std::vector<Track> tracks(3);
  tracks[0].rover = 0;
  tracks[0].points = {{1, 1}, {3, 1}, {5, 3.5}};
  tracks[0].metrics = {{"length_m", 5.5, "m"}, {"time_s", 20.0, "s"}};
  tracks[1].rover = 1;
  tracks[1].points = {{7, 9}};  // one point: a Point feature
  tracks[1].metrics = {{"length_m", 0.0, "m"},
                       {"energy_j", std::numeric_limits<double>::quiet_NaN(), "J"}};
  tracks[2].rover = 7;  // no points: no geometry

  const std::string json = tracksToGeoJson(tracks, kGrid, geo);
  CHECK(json.find("\"FeatureCollection\"") != std::string::npos);
  Parsed parsed(json);
  CHECK(OGR_L_GetFeatureCount(parsed.layer, TRUE) == 3);

  OGRFeatureDefnH defn = OGR_L_GetLayerDefn(parsed.layer);
  const int iRover = OGR_FD_GetFieldIndex(defn, "rover");
  const int iLength = OGR_FD_GetFieldIndex(defn, "length_m");
  const int iTime = OGR_FD_GetFieldIndex(defn, "time_s");
  const int iEnergy = OGR_FD_GetFieldIndex(defn, "energy_j");
  REQUIRE(iRover >= 0);
  REQUIRE(iLength >= 0);
  REQUIRE(iTime >= 0);
  REQUIRE(iEnergy >= 0);
  CHECK(OGR_Fld_GetType(OGR_FD_GetFieldDefn(defn, iRover)) == OFTInteger);
  CHECK(OGR_Fld_GetType(OGR_FD_GetFieldDefn(defn, iLength)) == OFTReal);
  CHECK(OGR_Fld_GetType(OGR_FD_GetFieldDefn(defn, iTime)) == OFTReal);

  OGR_L_ResetReading(parsed.layer);
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    OGRFeatureH f = OGR_L_GetNextFeature(parsed.layer);
    REQUIRE(f != nullptr);
    CAPTURE(k);
    CHECK(OGR_F_GetFieldAsInteger(f, iRover) == tracks[k].rover);
    OGRGeometryH geom = OGR_F_GetGeometryRef(f);
    if (k == 0) {
      REQUIRE(geom != nullptr);
      CHECK(wkbFlatten(OGR_G_GetGeometryType(geom)) == wkbLineString);
      REQUIRE(OGR_G_GetPointCount(geom) == 3);
      for (int i = 0; i < 3; ++i)
        checkNear({OGR_G_GetX(geom, i), OGR_G_GetY(geom, i)},
                  localToCrs(kGrid, geo, tracks[0].points[i]), 1e-12);
      CHECK(OGR_F_GetFieldAsDouble(f, iLength) == doctest::Approx(5.5));
      CHECK(OGR_F_GetFieldAsDouble(f, iTime) == doctest::Approx(20.0));
      CHECK(!OGR_F_IsFieldSetAndNotNull(f, iEnergy));
    } else if (k == 1) {
      REQUIRE(geom != nullptr);
      CHECK(wkbFlatten(OGR_G_GetGeometryType(geom)) == wkbPoint);
      checkNear({OGR_G_GetX(geom, 0), OGR_G_GetY(geom, 0)},
                localToCrs(kGrid, geo, tracks[1].points[0]), 1e-12);
      CHECK(OGR_F_GetFieldAsDouble(f, iLength) == doctest::Approx(0.0));
      CHECK(!OGR_F_IsFieldSetAndNotNull(f, iEnergy));  // NaN is written as null
      CHECK(!OGR_F_IsFieldSetAndNotNull(f, iTime));
    } else {
      CHECK(geom == nullptr);
    }
    OGR_F_Destroy(f);
  }
}

TEST_CASE("geojson: the layer CRS round-trips for EPSG:32633 and a Mars equirectangular CRS") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {-120000, 1, 0, 300000, 0, -1};
  std::vector<Track> tracks(1);
  tracks[0].points = {{0, 0}, {10, 20}};

  SUBCASE("EPSG:32633 is written as an OGC URN") {
    geo.crsWkt = wktFrom("EPSG:32633");
    const std::string json = tracksToGeoJson(tracks, kGrid, geo);
    CHECK(json.find("urn:ogc:def:crs:EPSG::32633") != std::string::npos);
    Parsed parsed(json);
    OGRSpatialReferenceH srs = OGR_L_GetSpatialRef(parsed.layer);
    REQUIRE(srs != nullptr);
    CHECK(std::string(OSRGetAuthorityName(srs, nullptr)) == "EPSG");
    CHECK(std::string(OSRGetAuthorityCode(srs, nullptr)) == "32633");
  }
  SUBCASE("Mars equirectangular (no authority code) is written as its WKT") {
    geo.crsWkt = wktFrom("+proj=eqc +R=3396190 +units=m +no_defs");
    const std::string json = tracksToGeoJson(tracks, kGrid, geo);
    CHECK(json.find("\"crs\"") != std::string::npos);
    CHECK(json.find("3396190") != std::string::npos);
    Parsed parsed(json);
    OGRSpatialReferenceH srs = OGR_L_GetSpatialRef(parsed.layer);
    REQUIRE(srs != nullptr);
    OGRSpatialReferenceH original = OSRNewSpatialReference(geo.crsWkt.c_str());
    CHECK(OSRIsSame(srs, original));
    CHECK(OSRGetSemiMajor(srs, nullptr) == doctest::Approx(3396190.0));
    OSRDestroySpatialReference(original);
    // Coordinates are unchanged by the CRS (no reprojection to WGS 84).
    OGR_L_ResetReading(parsed.layer);
    OGRFeatureH f = OGR_L_GetNextFeature(parsed.layer);
    REQUIRE(f != nullptr);
    OGRGeometryH geom = OGR_F_GetGeometryRef(f);
    REQUIRE(geom != nullptr);
    checkNear({OGR_G_GetX(geom, 1), OGR_G_GetY(geom, 1)}, localToCrs(kGrid, geo, {10, 20}));
    OGR_F_Destroy(f);
  }
  SUBCASE("no CRS when the map has none") {
    geo.crsWkt.clear();
    const std::string json = tracksToGeoJson(tracks, kGrid, geo);
    CHECK(json.find("\"crs\"") == std::string::npos);
    Parsed parsed(json);
    CHECK(OGR_L_GetFeatureCount(parsed.layer, TRUE) == 1);
  }
  SUBCASE("an unparsable CRS is an input error") {
    geo.crsWkt = "not a CRS";
    try {
      tracksToGeoJson(tracks, kGrid, geo);
      FAIL("no error for a bad CRS");
    } catch (const rover::Error& e) {
      CHECK(e.code() == rover::ErrorCode::InvalidInput);
      CHECK(e.field() == "crs");
    }
  }
}

TEST_CASE("geojson: an empty track list is a valid empty FeatureCollection") {
  const std::string json = tracksToGeoJson({}, kGrid, GeoReference{});
  Parsed parsed(json);
  CHECK(OGR_L_GetFeatureCount(parsed.layer, TRUE) == 0);
}

TEST_CASE("geojson: ogrinfo reads the document") {
  if (std::system("command -v ogrinfo > /dev/null 2>&1") != 0) {
    MESSAGE("ogrinfo is not on PATH; skipped");
    return;
  }
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {0, 1, 0, 100, 0, -1};
  std::vector<Track> tracks(2);
  tracks[0].rover = 0;
  tracks[0].points = {{0, 0}, {10, 20}, {30, 5}};
  tracks[0].metrics = {{"length_m", 51.2, "m"}};
  tracks[1].rover = 1;
  tracks[1].points = {{4, 4}};
  for (const char* crs : {"EPSG:32633", "+proj=eqc +R=3396190 +units=m +no_defs", ""}) {
    CAPTURE(crs);
    geo.crsWkt = *crs ? wktFrom(crs) : "";
    const auto dir = std::filesystem::temp_directory_path();
    const auto file = dir / ("rover_test_geojson_" + std::to_string(::getpid()) + ".geojson");
    {
      std::ofstream out(file, std::ios::binary);
      out << tracksToGeoJson(tracks, kGrid, geo);
    }
    const std::string cmd = "ogrinfo -ro -al -so '" + file.string() + "' > /dev/null 2>&1";
    CHECK(std::system(cmd.c_str()) == 0);
    std::filesystem::remove(file);
  }
}

TEST_CASE("geojson: a mission's route, targets, zones and incidents beside its tracks, by layer") {
  GeoReference geo;
  geo.valid = true;
  geo.geotransform = {500000, 2, 0, 4000000, 0, -2};
  geo.crsWkt = wktFrom("EPSG:32633");
  rover::PlanResult r;
  r.tracks.resize(2);
  r.tracks[0].rover = 0;
  r.tracks[0].points = {{0, 0}, {3, 4}};
  r.tracks[0].samples = {{0.0, {0, 0}}, {12.5, {3, 4}}};
  r.tracks[1].rover = 1;
  r.tracks[1].points = {{10, 10}, {10, 20}};
  r.overlays = {{"route", -1, {{5, 5}, {20, 20}, {40, 20}}}, {"path", 0, {{0, 0}, {1, 1}}}};
  r.targets = {{0, {20, 20}, rover::TargetStatus::Reached, 2, 0, 0, 0}, {1, {40, 20}, rover::TargetStatus::Skipped, 0, 0, 2, 0}};
  r.incidents = {{rover::IncidentKind::Skipped, 1, -1, 30.0, {40, 20}, 1.0, "target 1: given up", -1, "no_path"}};
  Zone z;
  z.rings = {{{50, 50}, {60, 50}, {60, 60}, {50, 60}}};
  z.name = "crater rim";
  const std::string json = missionToGeoJson(r, {z}, kGrid, geo);
  Parsed parsed(json);
  CHECK(std::string(OGR_L_GetName(parsed.layer)) == "mission");
  CHECK(OGR_L_GetFeatureCount(parsed.layer, TRUE) == 2 + 1 + 2 + 1 + 1);  // the path overlay is not exported
  OGRFeatureDefnH defn = OGR_L_GetLayerDefn(parsed.layer);
  const int iLayer = OGR_FD_GetFieldIndex(defn, "layer"), iStatus = OGR_FD_GetFieldIndex(defn, "status");
  const int iLength = OGR_FD_GetFieldIndex(defn, "length_m"), iDuration = OGR_FD_GetFieldIndex(defn, "duration_s");
  const int iKind = OGR_FD_GetFieldIndex(defn, "kind"), iName = OGR_FD_GetFieldIndex(defn, "name");
  REQUIRE(iLayer >= 0);
  REQUIRE(iStatus >= 0);
  REQUIRE(iKind >= 0);
  std::vector<std::string> layers;
  OGR_L_ResetReading(parsed.layer);
  while (OGRFeatureH f = OGR_L_GetNextFeature(parsed.layer)) {
    const std::string layer = OGR_F_GetFieldAsString(f, iLayer);
    layers.push_back(layer);
    OGRGeometryH g = OGR_F_GetGeometryRef(f);
    REQUIRE(g != nullptr);
    const auto type = wkbFlatten(OGR_G_GetGeometryType(g));
    if (layer == "track") {
      CHECK(type == wkbLineString);
      if (layers.size() == 1) {
        CHECK(OGR_F_GetFieldAsDouble(f, iLength) == doctest::Approx(5.0));
        CHECK(OGR_F_GetFieldAsDouble(f, iDuration) == doctest::Approx(12.5));
      } else {
        CHECK(!OGR_F_IsFieldSetAndNotNull(f, iDuration));  // no clock
      }
    } else if (layer == "route") {
      CHECK(type == wkbLineString);
      CHECK(OGR_G_GetPointCount(g) == 3);
    } else if (layer == "target") {
      CHECK(type == wkbPoint);
      CHECK(std::string(OGR_F_GetFieldAsString(f, iStatus)) == (layers.size() == 4 ? "reached" : "skipped"));
    } else if (layer == "zone") {
      CHECK(type == wkbPolygon);
      CHECK(std::string(OGR_F_GetFieldAsString(f, iName)) == "crater rim");
      // The ring is closed and in the CRS: local (50, 50) is easting 500050, northing 4000000 − 200 + 50.
      OGRGeometryH ring = OGR_G_GetGeometryRef(g, 0);
      CHECK(OGR_G_GetPointCount(ring) == 5);
      CHECK(OGR_G_GetX(ring, 0) == doctest::Approx(500050));
      CHECK(OGR_G_GetY(ring, 0) == doctest::Approx(3999850));
    } else {
      CHECK(layer == "incident");
      CHECK(type == wkbPoint);
      CHECK(std::string(OGR_F_GetFieldAsString(f, iKind)) == "skipped");
    }
    OGR_F_Destroy(f);
  }
  CHECK(layers == std::vector<std::string>{"track", "track", "route", "target", "target", "zone", "incident"});
}
