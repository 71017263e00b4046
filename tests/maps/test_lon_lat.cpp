// Local frame -> longitude/latitude on the map's body (maps/lon_lat), for the MCAP replay's fixes.
#include <doctest/doctest.h>
#include <ogr_spatialref.h>

#include "maps/gdal_env.hpp"
#include "maps/lon_lat.hpp"

using namespace rover;

namespace {

std::string wktOf(int epsg) {
  maps::ensureGdal();
  OGRSpatialReference srs;
  REQUIRE(srs.importFromEPSG(epsg) == OGRERR_NONE);
  char* text = nullptr;
  srs.exportToWkt(&text);
  std::string out = text;
  CPLFree(text);
  return out;
}

}  // namespace

TEST_CASE("lon/lat of local: a projected map is unprojected, a geographic one read as it is, none without a CRS") {
  // 100 × 100 cells of 1 m whose south-west corner is UTM 33N (500 000 E, 0 N): the equator at 15° E.
  const GridGeometry g{100, 100, 1.0, 1.0};
  GeoReference utm{{500000.0, 1.0, 0.0, 100.0, 0.0, -1.0}, wktOf(32633), true};
  const auto a = maps::LonLatOfLocal::make(g, utm);
  REQUIRE(a.has_value());
  const auto p = (*a)(Eigen::Vector2d(0, 0));
  REQUIRE(p.has_value());
  CHECK(p->x() == doctest::Approx(15.0).epsilon(1e-9));
  CHECK(p->y() == doctest::Approx(0.0).scale(1.0).epsilon(1e-9));
  // 100 m north of the equator is 100 / 110 574 m per degree of latitude (WGS 84 there).
  const auto q = (*a)(Eigen::Vector2d(0, 100));
  REQUIRE(q.has_value());
  CHECK(q->y() == doctest::Approx(100.0 / 110574.3).epsilon(1e-4));

  // WGS 84 degrees, 0.001° pixels from (10° E, 50° N) at the top-left: longitude first.
  GeoReference wgs{{10.0, 0.001, 0.0, 50.0, 0.0, -0.001}, wktOf(4326), true};
  const auto b = maps::LonLatOfLocal::make(g, wgs);
  REQUIRE(b.has_value());
  const auto c = (*b)(Eigen::Vector2d(0, 0));  // the south-west corner: 100 pixels below the top
  REQUIRE(c.has_value());
  CHECK(c->x() == doctest::Approx(10.0));
  CHECK(c->y() == doctest::Approx(49.9));

  CHECK_FALSE(maps::LonLatOfLocal::make(g, GeoReference{}).has_value());
  GeoReference noCrs = utm;
  noCrs.crsWkt.clear();
  CHECK_FALSE(maps::LonLatOfLocal::make(g, noCrs).has_value());
}
