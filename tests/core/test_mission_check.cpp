// One start check for every planner (issue 11): coverage, team-search and hybrid refuse the same
// start with the same field, code and words.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>

#include "core/common/error.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/planning/mission_check.hpp"
#include "core/planning/planner.hpp"
#include "core/terrain/body.hpp"

using namespace rover;

namespace {

// 40 × 40 m of flat ground at 1 m with one 1.04 m spike at (row 20, col 20): 46° to its
// neighbours, so it and its 8 neighbours are impassable; (row 5, col 30) has no data.
std::shared_ptr<terrain::Dem> siteDem() {
  auto d = std::make_shared<terrain::Dem>();
  d->z = Raster<float>(GridGeometry{40, 40, 1.0, 1.0}, 0.0f);
  d->z(20, 20) = 1.04f;
  d->z(5, 30) = NAN;
  return d;
}

PlanningProblem problemFor(const std::string& planner, std::vector<RoverStart> rovers) {
  PlanningProblem p;
  p.dem = siteDem();
  if (planner == "coverage") p.world = coverage::worldFromDem(*p.dem, 1.0);
  p.rovers = std::move(rovers);
  return p;
}

struct Refusal {
  std::string field, message;
  ErrorCode code = ErrorCode::NotFound;  // "accepted" when nothing was thrown
};

Refusal refusal(const std::string& planner, std::vector<RoverStart> rovers) {
  PlannerRegistry reg = makeBuiltinRegistry();
  try {
    reg.get(planner).validate(problemFor(planner, std::move(rovers)), {});
  } catch (const Error& e) {
    return {e.field(), e.what(), e.code()};
  }
  return {"", "accepted", ErrorCode::NotFound};
}

const RoverStart kFine{{10.5, 10.5}, 0.0};

}  // namespace

TEST_CASE(
    "mission check: the same bad start is refused alike by coverage, team-search and hybrid") {
  struct Case {
    const char* what;
    std::vector<RoverStart> rovers;
    std::string field;
  };
  const std::vector<Case> cases{
      {"on a 46° impassable cell", {kFine, {{20.5, 19.5}, 0.0}}, "rovers[1]"},
      {"on nodata", {{{30.5, 34.5}, 0.0}}, "rovers[0]"},
      {"next to nodata", {kFine, {{31.4, 34.5}, 0.0}}, "rovers[1]"},
      {"outside the map", {kFine, {{40.5, 3.0}, 0.0}}, "rovers[1]"},
      {"not finite", {{{NAN, 3.0}, 0.0}}, "rovers[0]"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.what);
    const Refusal cov = refusal("coverage", c.rovers);
    CHECK(cov.field == c.field);
    CHECK(cov.code == ErrorCode::InvalidInput);
    for (const char* team : {"team-search", "hybrid"}) {
      CAPTURE(team);
      const Refusal t = refusal(team, c.rovers);
      CHECK(t.field == cov.field);
      CHECK(t.code == cov.code);
      CHECK(t.message == cov.message);
    }
  }
  // The impassable start in words, the same for all three (before: coverage accepted it).
  CHECK(refusal("coverage", cases[0].rovers).message ==
        "rovers[1]: start is on impassable ground (a slope of 15° or more)");
  CHECK(refusal("hybrid", {kFine}).message == "accepted");
  CHECK(refusal("coverage", {kFine}).message == "accepted");
}

TEST_CASE(
    "mission check: rovers too close — the safety distance for teams, one cell for coverage") {
  const std::vector<RoverStart> close{kFine, {{11.2, 10.5}, 0.0}};  // 0.7 m apart, two cells
  CHECK(refusal("team-search", close).field == "rovers[1]");
  CHECK(refusal("team-search", close).message ==
        "rovers[1]: start is 0.7 m from rovers[0], closer than the safety distance of 1 m");
  CHECK(refusal("coverage", close).message == "accepted");
  const std::vector<RoverStart> shared{kFine, {{10.9, 10.1}, 0.0}};
  CHECK(refusal("coverage", shared).message ==
        "rovers[1]: start is in the same coverage cell as rovers[0]");
  CHECK(refusal("coverage", {}).field == "rovers");
  CHECK(refusal("team-search", {}).field == "rovers");
}

TEST_CASE(
    "mission check: a coverage cell made an obstacle by its neighbour pixel is refused by "
    "coverage") {
  // With 3 m coverage cells, the cell of pixels cols 21..23, rows 19..21 holds the impassable
  // pixel (20, 21), while the start's own pixel (20, 23) is passable: only the grid refuses it.
  PlanningProblem p;
  p.dem = siteDem();
  p.world = coverage::worldFromDem(*p.dem, 3.0);
  p.rovers = {{{23.5, 19.5}, 0.0}};
  PlannerRegistry reg = makeBuiltinRegistry();
  CHECK_THROWS_WITH_AS(
      reg.get("coverage").validate(p, {}),
      "rovers[0]: start is in a coverage cell that holds impassable ground or nodata", Error);
  p.dem.reset();  // a grid without its map (a random world): the grid's own words
  CHECK_THROWS_WITH_AS(reg.get("coverage").validate(p, {}), "rovers[0]: start is on an obstacle",
                       Error);
}

TEST_CASE("body: detected from the ellipsoid's axis or names, gravity per body") {
  using terrain::Body;
  CHECK(terrain::detectBody("Mars_2000_IAU_IAG", "D_Mars_2000", 3396190) == Body::Mars);
  CHECK(terrain::detectBody("", "", 3393400) == Body::Mars);
  CHECK(terrain::detectBody("Moon_2000_IAU_IAG", "", 1737400) == Body::Moon);
  CHECK(terrain::detectBody("WGS 84", "WGS_1984", 6378137) == Body::Earth);
  CHECK(terrain::detectBody("GRS 1980", "", 0) == Body::Earth);
  CHECK(terrain::detectBody("Lunar sphere", "", 0) == Body::Moon);
  CHECK(terrain::detectBody("unnamed", "", 1000) == Body::Unknown);
  CHECK(terrain::bodyGravity(Body::Mars) == 3.71);
  CHECK(terrain::bodyGravity(Body::Moon) == 1.62);
  CHECK(terrain::bodyGravity(Body::Earth) == 9.81);
}

TEST_CASE("body: coverage energy uses the map's body's gravity unless the user gives one") {
  PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("coverage");
  PlanningProblem p = problemFor("coverage", {kFine});
  ParamSet params{{"max_steps", std::int64_t{200}}};
  auto assumed = [](const PlanResult& r, const std::string& key) {
    for (const auto& [k, v] : r.assumptions)
      if (k == key) return v;
    return std::string();
  };
  PlanResult unknown = planner.run(p, params, nullptr, nullptr);
  CHECK(unknown.metric("gravity_m_s2") == 1.62);
  CHECK(assumed(unknown, "body") == "unknown");
  p.body = terrain::Body::Mars;
  PlanResult mars = planner.run(p, params, nullptr, nullptr);
  CHECK(mars.metric("gravity_m_s2") == 3.71);
  CHECK(assumed(mars, "body") == "mars");
  CHECK(mars.metric("energy_j") > unknown.metric("energy_j"));  // turns cost the same on every body
  params["gravity"] = 2.0;
  PlanResult given = planner.run(p, params, nullptr, nullptr);
  CHECK(given.metric("gravity_m_s2") == 2.0);
  CHECK(assumed(given, "gravity") == "given");
  // The per-map defaults the server shows.
  ParamSet d = coverage::coverageMapDefaults(p.dem->geometry(), terrain::Body::Mars);
  CHECK(std::get<double>(d["coverage_cell"]) == 1.0);
  CHECK(std::get<double>(d["gravity"]) == 3.71);
}

TEST_CASE("mission check: a map whose cell size is NaN, zero or infinite is refused, never planned on") {
  // Issue 22: a GeoTIFF with a NaN pixel size became a map with NaN cells, and a team-search or
  // hybrid mission on it segfaulted in checkMissionStarts. The core boundary refuses it by itself.
  for (double bad : {static_cast<double>(NAN), 0.0, -1.0, static_cast<double>(INFINITY)}) {
    CAPTURE(bad);
    for (const char* planner : {"coverage", "team-search", "hybrid"}) {
      CAPTURE(planner);
      PlanningProblem p = problemFor(planner, {kFine});
      auto dem = std::make_shared<terrain::Dem>(*p.dem);
      dem->z.geometry.cellWidth = bad;
      p.dem = dem;
      PlannerRegistry reg = makeBuiltinRegistry();
      try {
        reg.get(planner).validate(p, {});
        FAIL("accepted a map with cells of ", bad, " m");
      } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidInput);
        CHECK(e.field() == "map");
        CHECK(std::string(e.what()).find("the cell size must be finite positive metres") != std::string::npos);
      }
    }
  }
  // The start check on its own, as the server calls it.
  terrain::Dem nanCells = *siteDem();
  nanCells.z.geometry.cellHeight = NAN;
  planning::MissionGround ground;
  ground.dem = &nanCells;
  CHECK_THROWS_WITH_AS(planning::checkMissionStarts(ground, {kFine}, {}),
                       "map: the cell size must be finite positive metres, not 1 x nan m", Error);
  CHECK_THROWS_AS(checkGridGeometry(GridGeometry{0, 4, 1.0, 1.0}), Error);
  CHECK_NOTHROW(checkGridGeometry(GridGeometry{4, 4, 0.25, 0.25}));
}
