#include <doctest/doctest.h>

#include <algorithm>

#include "core/common/error.hpp"
#include "core/coverage/world.hpp"
#include "grid_literals.hpp"

using namespace rover;
using namespace rover::coverage;

TEST_CASE("random worlds: obstacle count, determinism by seed") {
  WorldParams p;  // 60×60, 5 %
  World a = generateWorld(p), b = generateWorld(p);
  CHECK(a.obstacleCount() == 180);
  CHECK(a.obstacles.values == b.obstacles.values);
  p.seed = 2;
  CHECK_FALSE(generateWorld(p).obstacles.values == a.obstacles.values);
}

TEST_CASE("sealed regions: allowed by default and counted, forbidden on request") {
  int sealedWorlds = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    WorldParams p;
    p.rows = p.cols = 30;
    p.obstacleFraction = 0.3;
    p.seed = seed;
    std::vector<int> sizes;
    freeComponents(generateWorld(p), sizes);
    sealedWorlds += sizes.size() > 1;

    p.allowSealed = false;
    World w = generateWorld(p);
    freeComponents(w, sizes);
    CHECK(sizes.size() == 1);        // every free cell reachable from every other
    CHECK(w.obstacleCount() > 200);  // the local test skips few placements
  }
  CHECK(sealedWorlds >= 3);  // 30 % obstacles often seal pockets off (7 of these 20 seeds)
}

TEST_CASE("reachability is 8-connected and can be confined to a region") {
  World w = test::worldFrom({
      "..#.",
      "..#.",
      "###.",
      "....",
  });
  // (0,3)..(3,3) column and bottom row connect to the left block only through... nothing:
  // the left 2×2 block is sealed by the '#' L-shape (diagonal (1,1)->(2,...) all blocked).
  auto fromTopLeft = reachableCells(w, {test::idx(w, 0, 0)});
  CHECK(std::count(fromTopLeft.begin(), fromTopLeft.end(), 1) == 4);
  auto fromRight = reachableCells(w, {test::idx(w, 0, 3)});
  CHECK(std::count(fromRight.begin(), fromRight.end(), 1) == 7);
  std::vector<std::uint8_t> region(16, 0);
  region[test::idx(w, 0, 3)] = region[test::idx(w, 1, 3)] = 1;
  auto confined = reachableCells(w, {test::idx(w, 0, 3)}, region);
  CHECK(std::count(confined.begin(), confined.end(), 1) == 2);
}

TEST_CASE("diagonal moves between corner-touching obstacles are allowed") {
  World w = test::worldFrom({
      ".#",
      "#.",
  });
  auto r = reachableCells(w, {0});
  CHECK(r[3] == 1);
}

TEST_CASE("bad worlds and parameters name their field") {
  WorldParams p;
  p.obstacleFraction = 0.95;
  CHECK_THROWS_WITH_AS(generateWorld(p), "obstacles: must be in [0, 0.9]", Error);
  p = WorldParams{};
  p.rows = 1;
  CHECK_THROWS_WITH_AS(generateWorld(p), "rows: must be in [2, 4096]", Error);
  World allRock = test::worldFrom({"##", "##"});
  CHECK_THROWS_WITH_AS(validateWorld(allRock), "the world has no free cell", Error);
  World w = test::worldFrom({"..", ".."});
  w.heights = Raster<double>(GridGeometry{3, 2, 1, 1}, 0.0);
  CHECK_THROWS_WITH_AS(validateWorld(w), "height grid size differs from the world", Error);
}
