#include <doctest/doctest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/synthetic_terrain.hpp"

using rover::maps::bodyCrsWkt;
using rover::maps::generateTerrain;
using rover::maps::SyntheticTerrainParams;
using rover::terrain::TerrainClass;

namespace {

SyntheticTerrainParams params(const std::string& preset, int size = 600, double cell = 0.25,
                              std::uint64_t seed = 1) {
  SyntheticTerrainParams p;
  p.preset = preset;
  p.size = size;
  p.cellSize = cell;
  p.seed = seed;
  return p;
}

bool sameHeights(const rover::terrain::Dem& a, const rover::terrain::Dem& b) {
  return a.z.values.size() == b.z.values.size() &&
         std::memcmp(a.z.values.data(), b.z.values.data(), a.z.values.size() * sizeof(float)) == 0;
}

// The field() of the rover::Error that fn throws ("<none>" if it throws nothing).
std::string errorField(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const rover::Error& e) {
    CHECK(e.code() == rover::ErrorCode::InvalidParameter);
    return e.field();
  }
  return "<none>";
}

struct Shares {
  double traversable, highRisk, impassable;
};

Shares shares(const rover::terrain::Dem& dem) {
  const auto t = rover::terrain::traversability(dem);
  return {t.shares.percent(TerrainClass::Traversable), t.shares.percent(TerrainClass::HighRisk),
          t.shares.percent(TerrainClass::Impassable)};
}

// Share of the cells of class `cls` that lie in 8-connected patches of at least `minSize` cells.
double shareInPatches(const rover::Raster<std::uint8_t>& classes, TerrainClass cls, int minSize) {
  const auto& g = classes.geometry;
  const auto value = static_cast<std::uint8_t>(cls);
  std::vector<char> seen(g.cellCount(), 0);
  long total = 0, inPatches = 0;
  std::vector<int> stack;
  for (int start = 0; start < g.cellCount(); ++start) {
    if (classes.at(start) != value || seen[start]) continue;
    long size = 0;
    stack.assign(1, start);
    seen[start] = 1;
    while (!stack.empty()) {
      const auto [r, c] = g.cell(stack.back());
      stack.pop_back();
      ++size;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          if (!g.contains(r + dr, c + dc)) continue;
          const int j = g.index(r + dr, c + dc);
          if (classes.at(j) != value || seen[j]) continue;
          seen[j] = 1;
          stack.push_back(j);
        }
      }
    }
    total += size;
    if (size >= minSize) inPatches += size;
  }
  return total == 0 ? 1.0 : static_cast<double>(inPatches) / static_cast<double>(total);
}

}  // namespace

TEST_CASE("synthetic terrain is deterministic for a seed and changes with it") {
  for (const char* preset : {"moon", "mars"}) {
    CAPTURE(preset);
    const auto a = generateTerrain(params(preset, 128, 0.25, 7));
    const auto b = generateTerrain(params(preset, 128, 0.25, 7));
    const auto c = generateTerrain(params(preset, 128, 0.25, 8));
    CHECK(sameHeights(a, b));
    CHECK_FALSE(sameHeights(a, c));
  }
}

TEST_CASE("synthetic terrain geometry, georeference and CRS") {
  const auto dem = generateTerrain(params("moon", 40, 2.0));
  const auto& g = dem.geometry();
  CHECK(g.rows == 40);
  CHECK(g.cols == 40);
  CHECK(g.cellWidth == 2.0);
  CHECK(g.cellHeight == 2.0);
  CHECK(dem.rowCellWidth.empty());
  CHECK(dem.z.geo.valid);
  // North-up, lower-left corner at (0, 0): the top edge is at y = 40 · 2 m.
  const std::array<double, 6> expected{0.0, 2.0, 0.0, 80.0, 0.0, -2.0};
  CHECK(dem.z.geo.geotransform == expected);
  CHECK(dem.z.geo.crsWkt == bodyCrsWkt("moon"));

  for (const auto& bodyRadius : {std::pair{"moon", 1737400.0}, std::pair{"mars", 3396190.0}}) {
    const char* const body = bodyRadius.first;  // not a structured binding: clang 14 cannot capture one
    const double radius = bodyRadius.second;
    CAPTURE(body);
    const std::string wkt = bodyCrsWkt(body);
    CHECK(wkt.find(std::to_string(static_cast<long>(radius))) != std::string::npos);
    OGRSpatialReference srs;
    REQUIRE(srs.importFromWkt(wkt.c_str()) == OGRERR_NONE);
    CHECK(srs.IsProjected());
    CHECK(srs.GetSemiMajor() == doctest::Approx(radius));
    CHECK(srs.GetSemiMinor() == doctest::Approx(radius));  // a sphere
    char* proj4 = nullptr;
    REQUIRE(srs.exportToProj4(&proj4) == OGRERR_NONE);
    CHECK(std::string(proj4).find("+proj=eqc") != std::string::npos);
    CPLFree(proj4);
  }
  CHECK(generateTerrain(params("mars", 16)).z.geo.crsWkt == bodyCrsWkt("mars"));
  CHECK(errorField([] { bodyCrsWkt("venus"); }) == "body");
}

TEST_CASE("synthetic terrain heights are all finite") {
  for (const char* preset : {"moon", "mars"}) {
    for (const auto& sizeCell :
         {std::pair{16, 0.25}, std::pair{600, 0.25}, std::pair{100, 10.0}, std::pair{64, 1000.0},
          std::pair{300, 0.01}, std::pair{16, 1e-300}}) {
      const int size = sizeCell.first;  // not a structured binding: clang 14 cannot capture one
      const double cell = sizeCell.second;
      CAPTURE(preset);
      CAPTURE(size);
      CAPTURE(cell);
      const auto dem = generateTerrain(params(preset, size, cell));
      CHECK(dem.z.values.allFinite());
    }
  }
}

TEST_CASE("moon terrain has crater bowls") {
  const auto dem = generateTerrain(params("moon"));
  const auto& z = dem.z.values;
  CHECK(z.maxCoeff() - z.minCoeff() > 1.0);
  // A bowl: some cell lies at least 0.5 m below every cell on the square ring 8 cells (2 m) away.
  const int n = 600, k = 8;
  int bowls = 0;
  for (int r = k; r < n - k; ++r) {
    for (int c = k; c < n - k; ++c) {
      float ring = z(r - k, c - k);
      for (int i = -k; i <= k; ++i) {
        ring = std::min({ring, z(r - k, c + i), z(r + k, c + i), z(r + i, c - k), z(r + i, c + k)});
      }
      if (ring - z(r, c) >= 0.5f) ++bowls;
    }
  }
  CHECK(bowls > 0);
}

TEST_CASE("synthetic terrain class shares at the defaults are near paper 001's site") {
  // Paper 001 §3.4 on Jezero: 89.50 / 8.36 / 2.14 %. Targets: 80–95 / 3–15 / 1–8 %.
  for (const char* preset : {"moon", "mars"}) {
    CAPTURE(preset);
    const auto dem = generateTerrain(params(preset));
    const auto s = shares(dem);
    CAPTURE(s.traversable);
    CAPTURE(s.highRisk);
    CAPTURE(s.impassable);
    CHECK(s.traversable >= 80.0);
    CHECK(s.traversable <= 95.0);
    CHECK(s.highRisk >= 3.0);
    CHECK(s.highRisk <= 15.0);
    CHECK(s.impassable >= 1.0);
    CHECK(s.impassable <= 8.0);

    // Impassable ground comes in features (crater walls, crests, rocks), not salt and pepper:
    // nearly all impassable cells belong to 8-connected patches of at least 8 cells.
    const auto t = rover::terrain::traversability(dem);
    CHECK(shareInPatches(t.classes, TerrainClass::Impassable, 8) > 0.85);
  }
}

TEST_CASE("synthetic terrain stays plausible on larger and coarser grids") {
  for (const char* preset : {"moon", "mars"}) {
    for (const auto& sizeCell : {std::pair{256, 2.0}, std::pair{300, 10.0}}) {
      const int size = sizeCell.first;  // not a structured binding: clang 14 cannot capture one
      const double cell = sizeCell.second;
      CAPTURE(preset);
      CAPTURE(size);
      CAPTURE(cell);
      const auto s = shares(generateTerrain(params(preset, size, cell)));
      CAPTURE(s.traversable);
      CAPTURE(s.highRisk);
      CAPTURE(s.impassable);
      CHECK(s.traversable >= 70.0);
      CHECK(s.traversable <= 99.0);
      CHECK(s.impassable >= 0.1);
      CHECK(s.impassable <= 12.0);
    }
  }
}

TEST_CASE("synthetic terrain feature multipliers") {
  // All features off: a flat plane at 0.
  for (const char* preset : {"moon", "mars"}) {
    auto p = params(preset, 64);
    p.craterDensity = p.rockDensity = p.relief = 0;
    const auto dem = generateTerrain(p);
    CHECK(dem.z.values.cwiseAbs().maxCoeff() == 0.0f);
  }
  // Rocks (0.2–1.5 m) are smaller than a 10 m cell, so they are not drawn there at all ...
  auto coarse = params("moon", 100, 10.0);
  auto coarseNoRocks = coarse;
  coarseNoRocks.rockDensity = 0;
  CHECK(sameHeights(generateTerrain(coarse), generateTerrain(coarseNoRocks)));
  // ... but on a 0.25 m grid they are.
  auto fine = params("moon", 100);
  auto fineNoRocks = fine;
  fineNoRocks.rockDensity = 0;
  CHECK_FALSE(sameHeights(generateTerrain(fine), generateTerrain(fineNoRocks)));
}

TEST_CASE("synthetic terrain rejects bad parameters, naming the field") {
  CHECK_THROWS_WITH_AS(generateTerrain(params("venus")),
                       "preset: must be moon or mars, not \"venus\"", rover::Error);
  CHECK_THROWS_WITH_AS(generateTerrain(params("mars", 15)), "size: must be in [16, 16384] cells",
                       rover::Error);
  CHECK_THROWS_WITH_AS(generateTerrain(params("mars", 600, 0.0)),
                       "cell: must be a number of metres in (0, 1000]", rover::Error);

  CHECK(errorField([] { generateTerrain(params("")); }) == "preset");
  CHECK(errorField([] { generateTerrain(params("Moon")); }) == "preset");
  CHECK(errorField([] { generateTerrain(params("moon", 16385)); }) == "size");
  CHECK(errorField([] { generateTerrain(params("moon", -1)); }) == "size");
  for (double cell : {-1.0, 1000.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    CAPTURE(cell);
    CHECK(errorField([cell] { generateTerrain(params("moon", 16, cell)); }) == "cell");
  }
  CHECK(errorField([] { generateTerrain(params("moon", 16, 1000.0)); }) == "<none>");
  CHECK(errorField([] {
          auto p = params("moon", 16);
          p.craterDensity = -0.5;
          generateTerrain(p);
        }) == "crater_density");
  CHECK(errorField([] {
          auto p = params("moon", 16);
          p.rockDensity = 11;
          generateTerrain(p);
        }) == "rock_density");
  CHECK(errorField([] {
          auto p = params("moon", 16);
          p.relief = std::nan("");
          generateTerrain(p);
        }) == "relief");
}
