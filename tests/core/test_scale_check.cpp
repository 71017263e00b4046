// Honest scale (issue 27): the warnings a map's cell size and heights raise, on literal values.
#include <doctest/doctest.h>

#include <cmath>

#include "core/planning/rover_range.hpp"
#include "core/terrain/scale_check.hpp"

using namespace rover::terrain;

TEST_CASE("scale: a rover-scale map on its body raises nothing") {
  CHECK(scaleWarnings(0.25, 0.25, -4500, -4380, Body::Mars).empty());  // HiRISE Gale
  CHECK(scaleWarnings(5.0, 5.0, -9100, 10780, Body::Moon).empty());     // the whole lunar relief, 5 m cells
  CHECK(scaleWarnings(1, 1, -8200, 21900, Body::Unknown).empty());
  CHECK(scaleWarnings(1, 1, NAN, NAN, Body::Mars).empty());  // all nodata: no height to judge
}

TEST_CASE("scale: cells over 5 m are coarser than a micro-rover can use") {
  const auto w = scaleWarnings(138, 465, -4000, 2000, Body::Mars);  // the MOLA-like map
  REQUIRE(w.size() == 1);
  CHECK(w[0].code == "coarse_cell");
  CHECK(w[0].field == "cell");
  CHECK(w[0].message.find("cells of 465 m") == 0);
  CHECK(scaleWarnings(5.01, 1, 0, 1, Body::Earth).size() == 1);
}

TEST_CASE("scale: radii are recognised and the offset that fixes them is named") {
  // A lunar file of radii (1 737 400 m ± relief).
  auto w = scaleWarnings(1, 1, 1'737'400 - 3000, 1'737'400 + 2500, Body::Moon);
  REQUIRE(w.size() == 1);
  CHECK(w[0].code == "heights_look_like_radii");
  CHECK(w[0].field == "vertical_offset");
  CHECK(w[0].message.find("the Moon") != std::string::npos);
  CHECK(w[0].message.find("vertical_offset=-1737400") != std::string::npos);
  // The ISIS3 cube of radii on a map whose body was not known: still the Moon's radius.
  w = scaleWarnings(100, 100, 1.730e6, 1.745e6, Body::Unknown);
  REQUIRE(w.size() == 2);
  CHECK(w[0].code == "coarse_cell");
  CHECK(w[1].code == "heights_look_like_radii");
  // Mars radii.
  w = scaleWarnings(1, 1, 3'396'190 - 5000, 3'396'190 + 5000, Body::Mars);
  REQUIRE(w.size() == 1);
  CHECK(w[0].message.find("vertical_offset=-3396190") != std::string::npos);
}

TEST_CASE("scale: heights outside the body's relief that are not radii") {
  // The MOLA file: −22 565 m is below anything on Mars.
  auto w = scaleWarnings(1, 1, -22'565, -1000, Body::Mars);
  REQUIRE(w.size() == 1);
  CHECK(w[0].code == "heights_out_of_range");
  CHECK(w[0].field == "vertical_scale");
  CHECK(w[0].message.find("Mars (-8.7 to 22.4 km)") != std::string::npos);
  // Raw counts far above any relief, on Earth.
  CHECK(scaleWarnings(1, 1, 0, 65535, Body::Earth)[0].code == "heights_out_of_range");
  // Olympus Mons is on Mars, not on the Moon.
  CHECK(scaleWarnings(1, 1, 0, 21'000, Body::Mars).empty());
  CHECK(scaleWarnings(1, 1, 0, 21'000, Body::Moon)[0].code == "heights_out_of_range");
}

TEST_CASE("rover range: a stated range or battery past which a rover went is one warning each") {
  using rover::planning::RoverRange;
  using rover::planning::rangeWarnings;
  const std::vector<double> distance{24'647'300, 1200}, energy{137e6, 5e3};
  CHECK(rangeWarnings({}, distance, energy).empty());  // nothing stated, nothing said
  auto w = rangeWarnings({2000, 0}, distance, energy);
  REQUIRE(w.size() == 1);
  CHECK(w[0] == "1 of 2 rovers drove more than the stated rover_range_m 2000 m (rover 1: 24647.3 km, x1.23e+04)");
  w = rangeWarnings({2000, 360e3}, distance, energy);
  REQUIRE(w.size() == 2);
  CHECK(w[1] == "1 of 2 rovers used more than the stated rover_energy_j 360000 J (rover 1: 137.0 MJ, x381)");
  CHECK(rangeWarnings({30'000'000, 1e9}, distance, energy).empty());
}
