#include <doctest/doctest.h>

#include <numbers>

#include "core/grid/direction.hpp"
#include "core/grid/geometry.hpp"

using namespace rover;

TEST_CASE("row 0 is north: cell centres in the local frame from the lower-left corner") {
  GridGeometry g{3, 4, 2.0, 2.0};                                 // 8 m wide, 6 m tall
  CHECK(cellToLocal(g, {2, 0}).isApprox(Eigen::Vector2d(1, 1)));  // bottom-left cell
  CHECK(cellToLocal(g, {0, 3}).isApprox(Eigen::Vector2d(7, 5)));  // top-right cell
}

TEST_CASE("localToCell inverts cellToLocal and rejects points outside") {
  GridGeometry g{5, 7, 0.5, 0.25};
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      auto back = localToCell(g, cellToLocal(g, {r, c}));
      REQUIRE(back);
      CHECK(*back == CellIndex{r, c});
    }
  CHECK_FALSE(localToCell(g, {-0.01, 0.1}));
  CHECK_FALSE(localToCell(g, {0.1, g.heightMetres() + 0.01}));
  CHECK_FALSE(localToCell(g, {std::nan(""), 0.1}));
  // The far edges belong to the last column / first row.
  CHECK(*localToCell(g, {g.widthMetres(), g.heightMetres()}) == CellIndex{0, 6});
  CHECK(*localToCell(g, {0, 0}) == CellIndex{4, 0});
}

TEST_CASE("directions turn counter-clockwise from east") {
  CHECK(kDirRow[2] == -1);  // north is up a row
  CHECK(kDirCol[0] == 1);
  CHECK(rotateDir(0, 2) == 2);
  CHECK(rotateDir(1, -2) == 7);
  CHECK(turnSteps(0, 2) == 2);
  CHECK(turnSteps(0, 6) == -2);
  CHECK(turnSteps(7, 1) == 2);
  CHECK(turnSteps(0, 4) == 4);
  CHECK(radiansToDir(std::numbers::pi / 2) == 2);
  CHECK(radiansToDir(-std::numbers::pi / 4) == 7);
  CHECK(isDiagonal(3));
  CHECK_FALSE(isDiagonal(4));
}
