#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::terrain;

namespace {
constexpr double kDeg = 180.0 / std::numbers::pi;

using rover::test::demFrom;
}  // namespace

TEST_CASE("Horn slope and aspect of planes") {
  // z rises 0.3 m per metre to the east: slope atan(0.3), facing west (aspect 270°).
  Dem east = demFrom(6, 7, 0.5, [](double x, double) { return 0.3 * x; });
  Raster<float> s = slopeHorn(east), a = aspectHorn(east);
  CHECK(std::isnan(s(0, 3)));  // borders are nodata, as gdaldem without -compute_edges
  CHECK(s(2, 3) == doctest::Approx(std::atan(0.3) * kDeg).epsilon(1e-5));
  CHECK(a(2, 3) == doctest::Approx(270.0));
  // Rising to the north faces south (180°); a plane rising north-east faces south-west (225°).
  Dem north = demFrom(5, 5, 1.0, [](double, double y) { return 0.2 * y; });
  CHECK(aspectHorn(north)(2, 2) == doctest::Approx(180.0));
  Dem ne = demFrom(5, 5, 1.0, [](double x, double y) { return 0.2 * (x + y); });
  CHECK(aspectHorn(ne)(2, 2) == doctest::Approx(225.0));
  CHECK(slopeHorn(ne)(2, 2) == doctest::Approx(std::atan(0.2 * std::sqrt(2.0)) * kDeg).epsilon(1e-5));
  // Flat cells have no aspect.
  Dem flat = demFrom(4, 4, 1.0, [](double, double) { return 5.0; });
  CHECK(std::isnan(aspectHorn(flat)(1, 1)));
  CHECK(slopeHorn(flat)(1, 1) == 0.0f);
}

TEST_CASE("hillshade: flat ground gets 1 + 254·sin(altitude), a slope facing the sun is brighter") {
  Dem flat = demFrom(4, 4, 1.0, [](double, double) { return 0.0; });
  CHECK(hillshade(flat)(1, 1) == doctest::Approx(1 + 254 * std::sin(45.0 / kDeg)));
  // Default sun from the north-west (315°): a slope facing north-west beats one facing south-east.
  Dem facingNW = demFrom(5, 5, 1.0, [](double x, double y) { return 0.3 * (x - y); });
  Dem facingSE = demFrom(5, 5, 1.0, [](double x, double y) { return -0.3 * (x - y); });
  CHECK(hillshade(facingNW)(2, 2) > hillshade(flat)(1, 1));
  CHECK(hillshade(facingSE)(2, 2) < hillshade(flat)(1, 1));
}

TEST_CASE("traversability: worst of the 8 neighbour slopes, classes at 10° and 15°") {
  auto classOf = [](double deg) {
    Dem d = demFrom(5, 5, 0.25, [deg](double x, double) { return std::tan(deg / kDeg) * x; });
    Traversability t = traversability(d, {}, true);
    CHECK(t.worstSlopeDeg(2, 2) == doctest::Approx(deg).epsilon(1e-4));
    return static_cast<TerrainClass>(t.classes(2, 2));
  };
  CHECK(classOf(5.0) == TerrainClass::Traversable);
  CHECK(classOf(9.9) == TerrainClass::Traversable);
  CHECK(classOf(10.1) == TerrainClass::HighRisk);
  CHECK(classOf(14.9) == TerrainClass::HighRisk);
  CHECK(classOf(15.1) == TerrainClass::Impassable);
}

TEST_CASE("traversability: a cone has its slope everywhere but the apex region") {
  // z = 0.2·r: 11.3° along the radius; the worst neighbour sees that slope on every cell.
  Dem cone = demFrom(41, 41, 0.5, [](double x, double y) { return 0.2 * std::hypot(x - 10.25, y - 10.25); });
  Traversability t = traversability(cone, {}, true);
  CHECK(t.worstSlopeDeg(5, 30) == doctest::Approx(std::atan(0.2) * kDeg).epsilon(0.02));
  CHECK(t.shares.percent(TerrainClass::HighRisk) > 99.0);
  TraversabilityParams strict;
  strict.highRiskDeg = 5;
  strict.impassableDeg = 8;
  CHECK(traversability(cone, strict).shares.percent(TerrainClass::Impassable) > 99.0);
  strict.highRiskDeg = 9;
  CHECK_THROWS_AS(traversability(cone, strict), Error);
}

TEST_CASE("nodata: a NaN cell is NoData, its neighbours ignore it, Horn windows with it are NaN") {
  Dem d = demFrom(5, 5, 1.0, [](double, double) { return 1.0; });
  d.z(2, 2) = NAN;
  d.z(0, 0) = 1000;  // a cliff two cells from the hole
  Traversability t = traversability(d);
  CHECK(static_cast<TerrainClass>(t.classes(2, 2)) == TerrainClass::NoData);
  CHECK(static_cast<TerrainClass>(t.classes(2, 3)) == TerrainClass::Traversable);
  CHECK(static_cast<TerrainClass>(t.classes(1, 1)) == TerrainClass::Impassable);
  CHECK(t.shares.counts[3] == 1);
  CHECK(t.shares.percent(TerrainClass::NoData) == doctest::Approx(4.0));
  CHECK(std::isnan(slopeHorn(d)(1, 2)));
  double total = 0;
  for (int k = 0; k < 4; ++k) total += t.shares.percent(static_cast<TerrainClass>(k));
  CHECK(total == doctest::Approx(100.0));
}

TEST_CASE("per-row east-west spacing (geographic rasters) scales the x slopes") {
  Dem d = demFrom(4, 6, 1.0, [](double x, double) { return 0.1 * x; });
  d.rowCellWidth = {1.0, 0.5, 0.5, 1.0};  // rows 1-2 are half as wide on the ground
  Traversability t = traversability(d, {}, true);
  CHECK(t.worstSlopeDeg(0, 2) == doctest::Approx(std::atan(0.1) * kDeg).epsilon(1e-4));
  CHECK(t.worstSlopeDeg(1, 2) == doctest::Approx(std::atan(0.2) * kDeg).epsilon(1e-4));
  CHECK(slopeHorn(d)(1, 2) == doctest::Approx(std::atan(0.2) * kDeg).epsilon(1e-4));
}

TEST_CASE("roll and pitch from the bilinear gradient (SPEC §2)") {
  Dem d = demFrom(10, 10, 1.0, [](double x, double y) { return 0.2 * x + 0.1 * y + 3; });
  auto s = surfaceAt(d, 4.3, 6.1);
  REQUIRE(s);
  CHECK(s->height == doctest::Approx(0.2 * 4.3 + 0.1 * 6.1 + 3).epsilon(1e-6));
  CHECK(s->dzdx == doctest::Approx(0.2));
  CHECK(s->dzdy == doctest::Approx(0.1));
  auto east = attitudeAt(d, 4.3, 6.1, 0.0);  // driving east: nose up by atan(0.2)
  CHECK(east->pitch == doctest::Approx(std::atan(0.2)));
  CHECK(east->roll == doctest::Approx(std::atan(0.1)));
  auto north = attitudeAt(d, 4.3, 6.1, std::numbers::pi / 2);
  CHECK(north->pitch == doctest::Approx(std::atan(0.1)));
  CHECK(north->roll == doctest::Approx(std::atan(-0.2)));
  auto west = attitudeAt(d, 4.3, 6.1, std::numbers::pi);
  CHECK(west->pitch == doctest::Approx(-std::atan(0.2)));
  CHECK_FALSE(surfaceAt(d, -0.1, 3));
  CHECK_FALSE(surfaceAt(d, 3, 10.5));
  d.z(4, 4) = NAN;
  CHECK_FALSE(surfaceAt(d, 4.5, 5.5));
}
