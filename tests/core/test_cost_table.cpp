#include <doctest/doctest.h>

#include "core/common/error.hpp"
#include "core/coverage/cost_table.hpp"

using namespace rover;
using namespace rover::coverage;

TEST_CASE("presets keep left and right apart and below the visited penalty") {
  for (const MotionCostTable& t : {spiralTable(), boustrophedonTable()}) {
    CHECK_NOTHROW(validateTable(t, "t"));
    for (int rel = 0; rel < 8; ++rel)
      for (int dir = 0; dir < 8; ++dir) CHECK(t.cost(rel, dir) < 1.1);
  }
  MotionCostTable s = spiralTable();
  // Spiral: left 90° < straight < right 90° (hug the covered side, paper 002 fig. 4b).
  CHECK(s.relative[2] < s.relative[0]);
  CHECK(s.relative[0] < s.relative[6]);
  // Boustrophedon: sweeping along x is cheaper than the lane shift.
  MotionCostTable b = boustrophedonTable();
  CHECK(b.cost(0, 0) < b.cost(0, 2));
  CHECK(b.cost(0, 4) < b.cost(0, 6));
}

TEST_CASE("tables from lists") {
  MotionCostTable t = tableFromList({0, 1, 2, 3, 4, 5, 6, 7}, "cost_table");
  CHECK(t.relative[3] == 3);
  CHECK(t.absolute[3] == 0);
  std::vector<double> sixteen{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  CHECK(tableToList(tableFromList(sixteen, "x")) == sixteen);
}

TEST_CASE("bad tables are rejected with the field name") {
  CHECK_THROWS_WITH_AS(tableFromList({1, 2, 3}, "cost_table"),
                       "cost_table: expected 8 relative costs, or 8 relative + 8 absolute", Error);
  CHECK_THROWS_WITH_AS(tableFromList({0, 1, 2, 3, 4, 5, -6, 7}, "cost_table"),
                       "cost_table: costs must be finite and >= 0", Error);
  // Equal left and right 90° costs would need a random tie-break (paper 002 §2.1).
  CHECK_THROWS_WITH_AS(tableFromList({0, 1, 2, 3, 4, 5, 2, 7}, "cost_table"),
                       "cost_table: left and right turns of 90° must have different costs "
                       "(paper 002 §2.1)",
                       Error);
}
