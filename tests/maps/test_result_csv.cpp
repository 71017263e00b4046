// result.csv (issue 13): both frames, the CRS's own column names, every sample of a clocked
// track, and a coverage track's heading, attitude and height derived from the DEM.
#include <doctest/doctest.h>
#include <ogr_srs_api.h>
#include <cpl_conv.h>

#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "maps/gdal_env.hpp"
#include "maps/result_csv.hpp"

using namespace rover;
using namespace rover::maps;

namespace {

GeoReference georef(const char* userInput) {
  ensureGdal();
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  REQUIRE(OSRSetFromUserInput(srs, userInput) == OGRERR_NONE);
  char* wkt = nullptr;
  REQUIRE(OSRExportToWkt(srs, &wkt) == OGRERR_NONE);
  GeoReference geo;
  geo.valid = true;
  geo.crsWkt = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  return geo;
}

std::vector<std::string> lines(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST_CASE("result csv: the CRS's column names") {
  CHECK(crsColumnNames(GeoReference{}) == std::pair<std::string, std::string>{"crs_x", "crs_y"});
  CHECK(crsColumnNames(georef("EPSG:32633")).first == "easting_m");
  CHECK(crsColumnNames(georef("EPSG:4326")) == std::pair<std::string, std::string>{"lon_deg", "lat_deg"});
  CHECK(crsColumnNames(georef("EPSG:2222")).first == "crs_x");  // Arizona East, in feet
}

TEST_CASE("result csv: a clocked track writes every sample, local and CRS coordinates") {
  const GridGeometry g{10, 20, 1.0, 1.0};  // 20 m × 10 m
  GeoReference geo = georef("EPSG:32633");
  geo.geotransform = {500000, 1, 0, 4000010, 0, -1};
  Track t;
  t.rover = 1;
  t.points = {{2, 3}};  // 1 Hz; the samples are what the CSV writes
  const double deg = std::numbers::pi / 180;
  t.samples = {{0.0, {2, 3}, 90 * deg, 1 * deg, -2 * deg, 0.25, 7.5},
               {0.1, {2, 3.025}, 90 * deg, 1 * deg, -2 * deg, 0.25, TrackSample::kNone}};
  const auto rows = lines(resultCsv({t}, g, geo, nullptr, {}));
  REQUIRE(rows.size() == 3);
  CHECK(rows[0] == "rover,time_s,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,speed_m_s,elevation_m");
  CHECK(rows[1] == "1,0.0,2.000,3.000,500002.000,4000003.000,90.00,1.00,-2.00,0.250,7.500");
  CHECK(rows[2] == "1,0.1,2.000,3.025,500002.000,4000003.025,90.00,1.00,-2.00,0.250,");  // unknown: empty
}

TEST_CASE("result csv: a coverage track's moves with heading, attitude and height from the DEM") {
  // A plane rising 0.1 m per metre to the east: heading east pitches up atan(0.1), north rolls.
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{10, 10, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 10; ++r)
    for (int c = 0; c < 10; ++c) dem.z(r, c) = static_cast<float>(0.1 * (c + 0.5));
  Track t;
  t.rover = 0;
  t.points = {{3.5, 3.5}, {4.5, 3.5}, {4.5, 3.5}, {4.5, 4.5}};  // east, a wait, north
  const auto rows = lines(resultCsv({t}, dem.geometry(), GeoReference{}, &dem, {std::numbers::pi / 2}));
  REQUIRE(rows.size() == 5);
  CHECK(rows[0] == "rover,move,x_m,y_m,crs_x,crs_y,heading_deg,roll_deg,pitch_deg,elevation_m");
  const double pitch = std::atan(0.1) * 180 / std::numbers::pi;  // 5.71°
  char buf[64];
  std::snprintf(buf, sizeof buf, "0,0,3.500,3.500,3.500,3.500,90.00,%.2f,0.00,0.350", -pitch);
  CHECK(rows[1] == buf);  // the start: its heading (north), the slope rises to its right
  std::snprintf(buf, sizeof buf, "0,1,4.500,3.500,4.500,3.500,0.00,0.00,%.2f,0.450", pitch);
  CHECK(rows[2] == buf);
  std::snprintf(buf, sizeof buf, "0,2,4.500,3.500,4.500,3.500,0.00,0.00,%.2f,0.450", pitch);
  CHECK(rows[3] == buf);  // a wait keeps the heading
  CHECK(rows[4].rfind("0,3,4.500,4.500,4.500,4.500,90.00,", 0) == 0);
}
