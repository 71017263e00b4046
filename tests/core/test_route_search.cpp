#include "core/team/route_search.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/common/error.hpp"
#include "core/grid/direction.hpp"
#include "core/pdm/pdm.hpp"
#include "core/terrain/layers.hpp"

using namespace rover;
using namespace rover::team;

namespace {

using Rows = std::vector<std::vector<float>>;

Raster<float> pdmFrom(const Rows& v, double cell = 1.0) {
  GridGeometry g{static_cast<int>(v.size()), static_cast<int>(v[0].size()), cell, cell};
  Raster<float> r(g, 0.0f);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) r(i, j) = v[i][j];
  return r;
}

// '.' traversable, 'h' high risk, '#' impassable, 'n' nodata.
Raster<std::uint8_t> classesFrom(const std::vector<std::string>& m, double cell = 1.0) {
  GridGeometry g{static_cast<int>(m.size()), static_cast<int>(m[0].size()), cell, cell};
  Raster<std::uint8_t> r(g, 0);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      terrain::TerrainClass t = terrain::TerrainClass::Traversable;
      if (m[i][j] == 'h') t = terrain::TerrainClass::HighRisk;
      if (m[i][j] == '#') t = terrain::TerrainClass::Impassable;
      if (m[i][j] == 'n') t = terrain::TerrainClass::NoData;
      r(i, j) = static_cast<std::uint8_t>(t);
    }
  return r;
}

// A search grid whose cells are the literal's cells (footprint = map cell = 1 m).
SearchGrid gridOf(const Rows& v, const std::vector<std::string>& mask = {}) {
  return makeSearchGrid(pdmFrom(v), mask.empty() ? Raster<std::uint8_t>{} : classesFrom(mask), 1.0);
}

RouteParams plain(int targets) {
  RouteParams p;
  p.targets = targets;
  p.globalWarming = false;
  return p;
}

std::string fieldOf(auto&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.field();
  }
  return "<no error>";
}

ErrorCode codeOf(auto&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  return ErrorCode::NotFound;
}

bool adjacent(CellIndex a, CellIndex b) {
  return std::max(std::abs(a.row - b.row), std::abs(a.col - b.col)) == 1;
}

}  // namespace

TEST_CASE("route: makeSearchGrid sums mass per footprint and marks impassable by majority") {
  // 4 × 4 map of 1 m cells, 2 m footprint → 2 × 2 search cells of 4 map cells each.
  Rows v = {{1, 2, 3, 4},  //
            {5, 6, 7, 8},
            {9, 10, 11, 12},
            {13, 14, 15, 16}};
  std::vector<std::string> m = {"#.##",  // NW: 2 of 4 blocked → 50 %, stays passable
                                "h#.#",  // NE: 3 of 4 blocked → impassable
                                "n#..",  // SW: nodata + impassable + ... 3 of 4 → impassable
                                ".#.h"}; // SE: 0 of 4 blocked (high risk is passable)
  SearchGrid sg = makeSearchGrid(pdmFrom(v), classesFrom(m), 2.0);
  REQUIRE(sg.rows() == 2);
  REQUIRE(sg.cols() == 2);
  CHECK(sg.cellSize() == 2.0);
  CHECK(sg.mass(0, 0) == 1 + 2 + 5 + 6);
  CHECK(sg.mass(0, 1) == 3 + 4 + 7 + 8);
  CHECK(sg.mass(1, 0) == 9 + 10 + 13 + 14);
  CHECK(sg.mass(1, 1) == 11 + 12 + 15 + 16);
  CHECK(sg.impassable(0, 0) == 0);
  CHECK(sg.impassable(0, 1) == 1);
  CHECK(sg.impassable(1, 0) == 1);
  CHECK(sg.impassable(1, 1) == 0);
  double total = 0;
  for (int i = 0; i < 4; ++i) total += sg.mass.at(i);
  CHECK(total == 136.0);  // every map cell's mass lands in exactly one search cell
  CHECK(sg.passableMass() == 14.0 + 54.0);
  // Centres in the local frame (x east, y north from the south-west corner).
  CHECK(sg.centre({0, 0}).isApprox(Eigen::Vector2d(1, 3)));
  CHECK(sg.centre({1, 1}).isApprox(Eigen::Vector2d(3, 1)));
  // Without classes, everything is passable.
  SearchGrid open = makeSearchGrid(pdmFrom(v), {}, 2.0);
  CHECK(open.passableMass() == 136.0);
}

TEST_CASE("route: a map that is not a whole number of footprints gets partial north/east cells") {
  Rows v(5, std::vector<float>(5, 1.0f));
  v[0][0] = 10;  // north-west map cell → partial search row 0
  SearchGrid sg = makeSearchGrid(pdmFrom(v), {}, 2.0);
  REQUIRE(sg.rows() == 3);
  REQUIRE(sg.cols() == 3);
  CHECK(sg.mass(0, 0) == 10 + 1);          // map row 0, cols 0-1
  CHECK(sg.mass(0, 2) == 1);               // map row 0, col 4
  CHECK(sg.mass(1, 1) == 4);               // map rows 1-2, cols 2-3
  CHECK(sg.mass(2, 2) == 2);               // map rows 3-4, col 4
  double total = 0;
  for (int i = 0; i < sg.geometry().cellCount(); ++i) total += sg.mass.at(i);
  CHECK(total == 34.0);
  CHECK(sg.centre({0, 2}).isApprox(Eigen::Vector2d(4.5, 4.5)));  // the part inside the map
  CHECK(sg.centre({2, 0}).isApprox(Eigen::Vector2d(1, 1)));
  CHECK(sg.centre({1, 2}).isApprox(Eigen::Vector2d(4.5, 3)));
}

TEST_CASE("route: a 150 m site at 0.25 m with a 5 m footprint gives 30 x 30, total preserved") {
  GridGeometry g{600, 600, 0.25, 0.25};
  Raster<float> p = pdm::discretise(pdm::randomGaussians(g, 4, 11), g);
  SearchGrid sg = makeSearchGrid(p, {}, 5.0);
  CHECK(sg.rows() == 30);
  CHECK(sg.cols() == 30);
  double total = 0;
  for (int i = 0; i < g.cellCount(); ++i) total += p.at(i);
  CHECK(sg.passableMass() == doctest::Approx(total).epsilon(1e-9));
  CHECK(sg.centre({29, 0}).isApprox(Eigen::Vector2d(2.5, 2.5)));
}

TEST_CASE("route: hill climbing follows the gradient") {
  SearchGrid sg = gridOf({{0, 1, 2, 3, 4},  //
                          {1, 2, 3, 4, 5},
                          {2, 3, 4, 5, 6},
                          {3, 4, 5, 6, 9}});
  Route r = lhcGwConv(sg, {0, 0}, plain(4));
  REQUIRE(r.cells.size() == 4);
  CHECK(r.cells[0] == CellIndex{1, 1});
  CHECK(r.cells[1] == CellIndex{2, 2});
  CHECK(r.cells[2] == CellIndex{3, 3});
  CHECK(r.cells[3] == CellIndex{3, 4});
  CHECK(r.score == 0 + 2 + 4 + 6 + 9);
  CHECK(r.distinctCells == 5);
  CHECK(r.warmingLevel == 0);
  CHECK(r.levelScores.size() == 1);
  CHECK(r.centres[3].isApprox(Eigen::Vector2d(4.5, 0.5)));
  CHECK(r.startCentre.isApprox(Eigen::Vector2d(0.5, 3.5)));
}

TEST_CASE("route: equal values are broken by the higher 3x3 blur, then by neighbour order") {
  // From (1,2) the W and E neighbours both hold 5; the mass at (2,0) lifts W's blur.
  Rows west = {{0, 0, 0, 0, 0},  //
               {0, 5, 0, 5, 0},
               {3, 0, 0, 0, 0},
               {0, 0, 0, 0, 0}};
  Route r = lhcGwConv(gridOf(west), {1, 2}, plain(1));
  CHECK(r.cells[0] == CellIndex{1, 1});
  // Mirrored: the extra mass on the east side.
  Rows east = {{0, 0, 0, 0, 0},  //
               {0, 5, 0, 5, 0},
               {0, 0, 0, 0, 3},
               {0, 0, 0, 0, 0}};
  r = lhcGwConv(gridOf(east), {1, 2}, plain(1));
  CHECK(r.cells[0] == CellIndex{1, 3});
  // Without the convolution tie-break the fixed order (E first) decides.
  RouteParams noConv = plain(1);
  noConv.convolutionTieBreak = false;
  r = lhcGwConv(gridOf(west), {1, 2}, noConv);
  CHECK(r.cells[0] == CellIndex{1, 3});
  // Equal values and equal blurs: fixed order E, NE, N, NW, W, SW, S, SE → N beats S here.
  Rows sym = {{0, 0, 7, 0, 0},  //
              {0, 0, 0, 0, 0},
              {0, 0, 7, 0, 0},
              {0, 0, 0, 0, 0}};
  r = lhcGwConv(gridOf(sym), {1, 2}, plain(1));
  CHECK(r.cells[0] == CellIndex{0, 2});
  // All neighbours 0: the blur looks one cell further and heads for the mass at distance 2.
  Rows far = {{0, 0, 0, 0, 0},  //
              {0, 0, 0, 0, 0},
              {0, 0, 0, 0, 0},
              {4, 0, 0, 0, 0}};
  r = lhcGwConv(gridOf(far), {1, 2}, plain(2));
  CHECK(r.cells[0] == CellIndex{2, 1});
  CHECK(r.cells[1] == CellIndex{3, 0});
}

TEST_CASE("route: zeroing prevents revisits until everything around is 0") {
  Rows v = {{1, 1, 1, 0, 0},  //
            {1, 1, 1, 0, 0},
            {1, 1, 1, 0, 0},
            {0, 0, 0, 0, 0}};
  SearchGrid sg = gridOf(v);
  Route r = lhcGwConv(sg, {0, 0}, plain(30));
  REQUIRE(r.cells.size() == 30);
  std::set<std::pair<int, int>> visited{{0, 0}};
  CellIndex prev{0, 0};
  bool revisited = false;
  for (const CellIndex& c : r.cells) {
    CHECK(adjacent(prev, c));
    if (visited.count({c.row, c.col}) != 0) {
      revisited = true;
      // A revisit happens only when every neighbour of the cell just left is seen or worthless.
      for (int d = 0; d < kDirections; ++d) {
        const int nr = prev.row + kDirRow[d];
        const int nc = prev.col + kDirCol[d];
        if (!sg.geometry().contains(nr, nc)) continue;
        CHECK((visited.count({nr, nc}) != 0 || v[nr][nc] == 0));
      }
    }
    visited.insert({c.row, c.col});
    prev = c;
  }
  CHECK(revisited);
  // The first 6 moves are all new cells; the whole block (mass 9) is collected.
  std::set<std::pair<int, int>> first{{0, 0}};
  for (int i = 0; i < 6; ++i) first.insert({r.cells[i].row, r.cells[i].col});
  CHECK(first.size() == 7);
  CHECK(r.score == 9.0);
  Route ten = lhcGwConv(sg, {0, 0}, plain(10));
  CHECK(ten.score == 9.0);  // zeroing steers the climb back to the two cells left behind
}

TEST_CASE("route: global warming escapes a small local peak for a big region across a valley") {
  // Start at (1,0) among 2s; a valley (column 2) separates it from the 7-9 region.
  Rows v = {{2, 2, 0, 8, 9},  //
            {1, 2, 0, 9, 9},
            {2, 2, 0, 8, 9},
            {1, 1, 0, 7, 8}};
  SearchGrid sg = gridOf(v);
  Route lhc = lhcGwConv(sg, {1, 0}, plain(4));
  CHECK(lhc.score == 1 + 2 + 2 + 2 + 1);  // stays among the 2s and 1s
  RouteParams gw;
  gw.targets = 4;  // l = 20 → C = 9 / 20 = 0.45; from k = 5 (2.25) the 2s are flattened
  Route r = lhcGwConv(sg, {1, 0}, gw);
  CHECK(r.score > lhc.score);
  CHECK(r.score == 1 + 2 + 0 + 9 + 9);
  CHECK(r.warmingLevel > 0);
  CHECK(r.warmingLevel == 5);  // ties between levels go to the smallest k
  REQUIRE(r.levelScores.size() == 21);
  CHECK(r.levelScores[0] == lhc.score);
  CHECK(r.cells[1] == CellIndex{1, 2});  // through the valley
  CHECK(r.cells[2] == CellIndex{1, 3});
}

TEST_CASE("route: impassable search cells are never targets") {
  Rows v = {{1, 9, 9, 9, 1},  //
            {1, 9, 2, 9, 1},
            {1, 9, 9, 9, 1},
            {3, 3, 3, 3, 3}};
  std::vector<std::string> m = {".###.",  //
                                ".#.#.",
                                ".###.",
                                "....."};
  SearchGrid sg = gridOf(v, m);
  for (CellIndex start : {CellIndex{0, 0}, CellIndex{3, 2}, CellIndex{1, 4}}) {
    for (bool gw : {false, true}) {
      RouteParams p;
      p.targets = 40;
      p.globalWarming = gw;
      Route r = lhcGwConv(sg, start, p);
      for (const CellIndex& c : r.cells) CHECK(sg.impassable(c.row, c.col) == 0);
      // (1,2) is walled off from outside: never reached, so at most the outer ring's 21.
      CHECK(r.score <= 3 + 3 + 15);
      CHECK(r.score >= 12);
    }
    Route lm = lawnmower(sg, start, 100);
    for (const CellIndex& c : lm.cells) CHECK(sg.impassable(c.row, c.col) == 0);
  }
}

TEST_CASE("route: in a dead end with nothing within the blur's reach the climb oscillates") {
  // Paper 001 §3.5: zeroing only "strongly discourages" revisits. With every neighbour and every
  // neighbour's 3×3 window at 0, the fixed order decides; in a 1-wide corridor that is a 2-cycle.
  Rows v = {{0, 0, 0, 0, 0},  //
            {0, 0, 0, 0, 0},
            {0, 0, 0, 0, 0},
            {0, 0, 0, 0, 0}};
  std::vector<std::string> corridor = {".....",  //
                                       "#####",
                                       "#####",
                                       "#####"};
  Route r = lhcGwConv(gridOf(v, corridor), {0, 4}, plain(4));
  std::vector<CellIndex> expect{{0, 3}, {0, 4}, {0, 3}, {0, 4}};  // E before W
  CHECK(r.cells == expect);
  // One unit of mass two cells down the corridor is seen through the blur and breaks the cycle.
  v[0][1] = 1;
  r = lhcGwConv(gridOf(v, corridor), {0, 4}, plain(4));
  expect = {{0, 3}, {0, 2}, {0, 1}, {0, 2}};
  CHECK(r.cells == expect);
}

TEST_CASE("route: walled in, the climb jumps to the best passable cell at distance 2, else ends") {
  Rows v = {{1, 0, 0, 0, 6},  //
            {0, 9, 9, 9, 0},
            {0, 9, 0, 9, 0},
            {2, 9, 9, 9, 0}};
  std::vector<std::string> ring = {".....",  //
                                   ".###.",
                                   ".#.#.",
                                   ".###."};
  SearchGrid sg = gridOf(v, ring);
  Route r = lhcGwConv(sg, {2, 2}, plain(2));
  CHECK(r.cells[0] == CellIndex{0, 4});
  CHECK(r.cells[1] == CellIndex{0, 3});  // 0-valued, 0-blur tie: W comes before S
  std::vector<std::string> sealed = {"#####",  //
                                     "#####",
                                     "##.##",
                                     "#####"};
  SearchGrid shut = gridOf(v, sealed);
  Route s = lhcGwConv(shut, {2, 2}, plain(3));
  CHECK(s.cells.empty());  // the walled-in start never becomes a target
  CHECK(s.score == 0.0);
  CHECK(s.distinctCells == 1);
}

TEST_CASE("route: lawnmower sweeps the rows in serpentine order from the start") {
  Rows v(4, std::vector<float>(5, 1.0f));
  SearchGrid sg = gridOf(v);
  Route r = lawnmower(sg, {0, 0}, 100);
  std::vector<CellIndex> expect;
  for (int c = 1; c < 5; ++c) expect.push_back({0, c});
  for (int c = 4; c >= 0; --c) expect.push_back({1, c});
  for (int c = 0; c < 5; ++c) expect.push_back({2, c});
  for (int c = 4; c >= 0; --c) expect.push_back({3, c});
  CHECK(r.cells == expect);
  CHECK(r.score == 20.0);
  CHECK(r.distinctCells == 20);
  CHECK(r.warmingLevel == 0);

  // From the middle, skipping an impassable cell: start row east, rows below, rows above, rest.
  std::vector<std::string> m = {".....",  //
                                ".....",
                                "..#..",
                                "....."};
  SearchGrid holed = gridOf(v, m);
  r = lawnmower(holed, {1, 2}, 100);
  expect.clear();
  expect = {{1, 3}, {1, 4}, {2, 4}, {2, 3}, {2, 1}, {2, 0}, {3, 0}, {3, 1}, {3, 2},
            {3, 3}, {3, 4}, {0, 4}, {0, 3}, {0, 2}, {0, 1}, {0, 0}, {1, 1}, {1, 0}};
  CHECK(r.cells == expect);
  Route three = lawnmower(holed, {1, 2}, 3);
  REQUIRE(three.cells.size() == 3);
  CHECK(three.cells[2] == CellIndex{2, 4});
  CHECK(three.centres[2].isApprox(Eigen::Vector2d(4.5, 1.5)));
}

TEST_CASE("route: accumulated probability vs distance along the route") {
  SearchGrid sg = gridOf({{0, 1, 2, 3, 4},  //
                          {1, 2, 3, 4, 5},
                          {2, 3, 4, 5, 6},
                          {3, 4, 5, 6, 9}});
  Route r = lhcGwConv(sg, {0, 0}, plain(4));
  auto acc = accumulatedAlongRoute(sg, r);
  REQUIRE(acc.size() == 5);
  CHECK(acc[0].first == 0.0);
  CHECK(acc[0].second == 0.0);
  CHECK(acc[1].first == doctest::Approx(std::sqrt(2.0)));
  CHECK(acc[1].second == 2.0);
  CHECK(acc[3].first == doctest::Approx(3 * std::sqrt(2.0)));
  CHECK(acc[4].first == doctest::Approx(3 * std::sqrt(2.0) + 1));
  CHECK(acc.back().second == r.score);
  // A revisit adds distance but no mass.
  Route back = r;
  back.cells.push_back({3, 3});
  auto acc2 = accumulatedAlongRoute(sg, back);
  CHECK(acc2.back().first == doctest::Approx(acc[4].first + 1));
  CHECK(acc2.back().second == acc[4].second);
}

TEST_CASE("route: validation names the field") {
  SearchGrid sg = gridOf({{1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}});
  RouteParams p;
  p.targets = 0;
  CHECK(fieldOf([&] { validateRouteParams(p); }) == "targets");
  CHECK(codeOf([&] { lhcGwConv(sg, {0, 0}, p); }) == ErrorCode::InvalidParameter);
  p.targets = 100001;
  CHECK(fieldOf([&] { lhcGwConv(sg, {0, 0}, p); }) == "targets");
  p.targets = 100000;
  p.warmingLevels = -1;
  CHECK(fieldOf([&] { validateRouteParams(p); }) == "warming_levels");
  p.warmingLevels = 1001;
  CHECK(fieldOf([&] { lhcGwConv(sg, {0, 0}, p); }) == "warming_levels");
  p.targets = 1;
  p.warmingLevels = 0;
  CHECK_NOTHROW(validateRouteParams(p));
  CHECK(lhcGwConv(sg, {0, 0}, p).levelScores.size() == 1);  // l = 0: k = 0 only
  CHECK(fieldOf([&] { lawnmower(sg, {0, 0}, 0); }) == "targets");
  CHECK(fieldOf([&] { lhcGwConv(sg, {4, 0}, RouteParams{}); }) == "start");
  CHECK(codeOf([&] { lhcGwConv(sg, {0, -1}, RouteParams{}); }) == ErrorCode::InvalidInput);
  CHECK(fieldOf([&] { lawnmower(sg, {0, 5}, 3); }) == "start");

  Raster<float> pdmRaster = pdmFrom({{1, 2}, {3, 4}});
  CHECK(fieldOf([&] { makeSearchGrid(pdmRaster, {}, 0.0); }) == "footprint_m");
  CHECK(fieldOf([&] { makeSearchGrid(pdmRaster, {}, 0.5); }) == "footprint_m");
  CHECK(fieldOf([&] { makeSearchGrid(pdmRaster, {}, std::nan("")); }) == "footprint_m");
  CHECK(fieldOf([&] { makeSearchGrid(pdmRaster, classesFrom({"...", "..."}), 1.0); }) ==
        "classes");
  CHECK(fieldOf([&] { makeSearchGrid(Raster<float>{}, {}, 1.0); }) == "pdm");
  Raster<float> negative = pdmFrom({{1, -2}, {3, 4}});
  CHECK(fieldOf([&] { makeSearchGrid(negative, {}, 1.0); }) == "pdm");
}

TEST_CASE("route: deterministic, and warming never loses to plain LHC on a random 30 x 30 site") {
  GridGeometry g{150, 150, 1.0, 1.0};
  Raster<float> p = pdm::discretise(pdm::randomGaussians(g, 4, 2024), g);
  SearchGrid sg = makeSearchGrid(p, {}, 5.0);
  REQUIRE(sg.rows() == 30);
  Route a = lhcGwConv(sg, {29, 0}, RouteParams{});
  Route b = lhcGwConv(sg, {29, 0}, RouteParams{});
  CHECK(a.cells == b.cells);
  CHECK(a.score == b.score);
  CHECK(a.warmingLevel == b.warmingLevel);
  CHECK(a.levelScores == b.levelScores);
  CHECK(a.cells.size() == 64);
  CHECK(a.centres.size() == 64);
  CHECK(a.levelScores.size() == 21);
  CHECK(a.warmingLevel >= 0);
  CHECK(a.warmingLevel <= 20);
  for (double s : a.levelScores) CHECK(a.score >= s);
  Route plainRoute = lhcGwConv(sg, {29, 0}, plain(64));
  CHECK(a.score >= plainRoute.score);
  CHECK(plainRoute.score == a.levelScores[0]);
  CellIndex prev{29, 0};
  for (const CellIndex& c : a.cells) {
    CHECK(adjacent(prev, c));  // no impassable cells here, so every move is to a neighbour
    prev = c;
  }
  Route lm = lawnmower(sg, {29, 0}, 64);
  CHECK(lm.cells.size() == 64);
  auto acc = accumulatedAlongRoute(sg, a);
  CHECK(acc.back().second == a.score);
  for (std::size_t i = 1; i < acc.size(); ++i) {
    CHECK(acc[i].first >= acc[i - 1].first + 5.0 - 1e-9);  // every move is one 5 m footprint or more
    CHECK(acc[i].second >= acc[i - 1].second);
  }
  CHECK(a.score <= sg.passableMass() + 1e-12);
}
