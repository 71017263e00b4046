// Which rovers can leave their starts while the others stand, and in what order (issue 25).
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/mission_check.hpp"
#include "core/team/coordination.hpp"
#include "core/team/formation.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::planning;

TEST_CASE("departure: a 3×3 block at the safety distance leaves from the outside in") {
  std::vector<Eigen::Vector2d> starts;
  for (int k = 0; k < 9; ++k) starts.emplace_back(k % 3, k / 3);
  const Departure d = departureOrder(starts, 1.0);
  CHECK(d.boxedIn.empty());
  CHECK(d.order == std::vector<int>{0, 1, 2, 3, 5, 6, 7, 8, 4});
  CHECK(d.firstRound == 8);  // the centre is held back
  // Spread to 2.25 m (the formation's start spacing) the centre is still planned last: the lanes
  // between its neighbours' safety discs are 0.25 m wide, no way out at safety_distance +
  // kDepartureMargin (issue 25: threading such lanes, 7 of 64 rovers never left).
  for (auto& s : starts) s *= 2.25;
  CHECK(departureOrder(starts, 1.0).order == std::vector<int>{0, 1, 2, 3, 5, 6, 7, 8, 4});
  // Spread to 3.1 m the lanes are 1.1 m wide, more than 2 × kDepartureMargin: all leave at once.
  for (auto& s : starts) s *= 3.1 / 2.25;
  CHECK(departureOrder(starts, 1.0).order == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8});
  CHECK(departureOrder(starts, 1.0).firstRound == 9);
}

TEST_CASE("departure: the generated formation leaves from the outside in") {
  // 16 rovers: formationSlots' 4 × 4 lattice in farthest-point order from the centre, spread to
  // the start spacing (2.25 m). Drawn with each rover's index at its slot (x east, y north):
  //    4   6   7   2
  //    8   0   9  10
  //   11  12   5  13
  //    3  14  15   1
  // The twelve outer rovers leave first, by index; the four inner ones (0, 5, 9, 12), whose
  // ways out are lanes 0.25 m wide between standing rovers' safety discs, after them.
  const std::vector<Eigen::Vector2d> slots = team::startSlots(16, 5.0, 1.0);
  REQUIRE(slots.size() == 16);
  const Departure d = departureOrder(slots, 1.0);
  CHECK(d.boxedIn.empty());
  CHECK(d.order == std::vector<int>{1, 2, 3, 4, 6, 7, 8, 10, 11, 13, 14, 15, 0, 5, 9, 12});
  CHECK(d.firstRound == 12);
}

TEST_CASE("departure: a rover in a pocket leaves after the rover in its mouth, or not at all") {
  // Passable ground: a 4 m square pocket, open to the east through a 1.5 m mouth, in open ground.
  const auto pocket = [](double mouth) {
    return [mouth](const Eigen::Vector2d& p) {
      const bool wall = (p.x() > -3 && p.x() < 3 && p.y() > -3 && p.y() < 3) &&
                        !(p.x() > -2 && p.x() < 2 && p.y() > -2 && p.y() < 2);
      const bool gap = p.x() >= 2 && std::abs(p.y()) < mouth / 2;
      return !wall || gap;
    };
  };
  // Rover 1 stands in the mouth: rover 0 leaves after it.
  const Departure open = departureOrder({{0, 0}, {2.5, 0}}, 1.0, pocket(1.5));
  CHECK(open.boxedIn.empty());
  CHECK(open.order == std::vector<int>{1, 0});
  // No mouth: rover 0 never gets out, rover 1 (outside) does.
  const Departure closed = departureOrder({{0, 0}, {4.5, 0}}, 1.0, pocket(0.0));
  CHECK(closed.order == std::vector<int>{1});
  CHECK(closed.boxedIn == std::vector<int>{0});
}

TEST_CASE("mission check: a team start with no way out is refused naming the rover") {
  // 20 × 20 m of flat ground at 1 m; impassable cells ring x and y in [5, 12), so a rover at
  // (8.5, 8.5) stands in a 5 m pocket with no way out.
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{20, 20, 1.0, 1.0}, 0.0f);
  Raster<std::uint8_t> classes(dem.z.geometry, 0);
  const auto wall = [&](int x, int y) {  // the cell of (x, y) metres: rows count from the north
    classes(19 - y, x) = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  };
  for (int i = 5; i <= 11; ++i)
    for (int j : {5, 11}) {
      wall(i, j);
      wall(j, i);
    }
  MissionGround ground;
  ground.dem = &dem;
  ground.classes = &classes;
  StartRules rules;
  rules.safetyDistance = 1.0;
  const std::vector<RoverStart> rovers{{{2.5, 2.5}, 0.0}, {{8.5, 8.5}, 0.0}};
  CHECK_NOTHROW(checkMissionStarts(ground, rovers, rules));  // without the rule
  rules.wayOut = true;
  try {
    checkMissionStarts(ground, rovers, rules);
    FAIL("accepted");
  } catch (const Error& e) {
    CHECK(e.field() == "rovers[1]");
    CHECK(e.code() == ErrorCode::InvalidInput);
    CHECK(std::string(e.what()).find("boxed in") != std::string::npos);
  }
}

TEST_CASE("formation: generated starts are never in a pocket the mission check refuses") {
  // 40 × 40 m of flat ground at 1 m; impassable cells ring x and y in [17, 24), so the ground
  // round the formation's centre (20.5, 20.5) is a 6 m pocket with no way out.
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{40, 40, 1.0, 1.0}, 0.0f);
  Raster<std::uint8_t> classes(dem.z.geometry, 0);
  const auto wall = [&](int x, int y) { classes(39 - y, x) = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable); };
  for (int i = 17; i <= 23; ++i)
    for (int j : {17, 23}) {
      wall(i, j);
      wall(j, i);
    }
  team::TeamMissionParams params;
  const std::vector<team::Pose> starts = team::formationStarts(dem, classes, params, {20.5, 20.5}, 5);
  REQUIRE(starts.size() == 5);
  MissionGround ground;
  ground.dem = &dem;
  ground.classes = &classes;
  StartRules rules;
  rules.safetyDistance = params.coordination.safetyDistance;
  rules.wayOut = true;
  std::vector<RoverStart> rovers;
  for (const team::Pose& s : starts) {
    CHECK_FALSE((s.x > 17 && s.x < 24 && s.y > 17 && s.y < 24));  // outside the pocket
    rovers.push_back({{s.x, s.y}, s.heading});
  }
  CHECK_NOTHROW(checkMissionStarts(ground, rovers, rules));
}

TEST_CASE("formation: no start on a shelf of passable ground the rover's moves do not connect") {
  // 24 × 24 m drawn at 1 m a character (dem_literals.hpp): a shelf 1 m high (x and y in [9, 17))
  // with vertical sides, and classes that call every cell passable — as on the Kepler site, where
  // the classes (slope over 3 × 3 cells) passed ground the attitude limit along every move out of
  // it does not: the pocket test (classes only) sees open ground, the traversal lattice a shelf
  // cut off from the rest. The formation round (8.5, 8.5) has its slot (+1.67, +1.67) on the shelf.
  std::vector<std::string> picture(24, std::string(24, '.'));
  for (int y = 9; y < 17; ++y)
    for (int x = 9; x < 17; ++x) picture[23 - y][x] = '#';
  const terrain::Dem dem = test::demFromPicture(picture);
  const Raster<std::uint8_t> classes(dem.geometry(), 0);
  team::TeamMissionParams params;
  const double safety = params.coordination.safetyDistance;
  // Without the lattice's test that slot would stand: a rover may stop and turn there, and the
  // passable ground round it is open.
  const Eigen::Vector2d onShelf(8.5 + 5.0 / 3, 8.5 + 5.0 / 3);
  const team::TerrainEdgeModel model = team::wholeMapModel(dem, classes, params.coordination.rrt);
  REQUIRE(model.turnValid(onShelf));
  REQUIRE(departureOrder({onShelf}, safety, passableGround(dem, &classes)).boxedIn.empty());
  const team::TraversalLattice lattice = team::makeLattice(dem, classes, params.coordination);
  REQUIRE(lattice.reachable({{8.5, 8.5}}).at(dem.geometry().index(*localToCell(dem.geometry(), onShelf))) == 0);

  const std::vector<team::Pose> starts = team::formationStarts(dem, classes, params, {8.5, 8.5}, 5);
  REQUIRE(starts.size() == 5);
  const Raster<std::uint8_t> ground = lattice.reachable({{starts[0].x, starts[0].y}});
  for (const team::Pose& s : starts) {
    CAPTURE(s.x);
    CAPTURE(s.y);
    CHECK_FALSE((s.x > 9 && s.x < 17 && s.y > 9 && s.y < 17));  // not on the shelf
    CHECK(lattice.startsWithin(ground, {s.x, s.y}));           // on the first start's ground
  }
  // The shelf itself is connected ground: a formation centred on it stays on it.
  for (const team::Pose& s : team::formationStarts(dem, classes, params, {13, 13}, 5))
    CHECK((s.x > 9 && s.x < 17 && s.y > 9 && s.y < 17));
}
