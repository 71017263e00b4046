#include <doctest/doctest.h>

#include "core/common/error.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/planning/planner.hpp"
#include "grid_literals.hpp"

using namespace rover;

TEST_CASE("planners are found by name, an unknown name is a NotFound on field planner") {
  PlannerRegistry reg = makeBuiltinRegistry();
  CHECK(reg.get("coverage").name() == "coverage");
  try {
    reg.get("teleport");
    FAIL("expected an error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::NotFound);
    CHECK(e.field() == "planner");
  }
  CHECK_THROWS_AS(reg.add(coverage::makeCoveragePlanner()), Error);  // no duplicates
}

TEST_CASE("the coverage planner validates the whole problem before running") {
  PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("coverage");
  PlanningProblem prob;
  prob.world = test::worldFrom({
      "....",
      ".#..",
      "....",
  });
  // Local frame: (1.5, 1.5) is row 1, col 1 — the obstacle.
  prob.rovers = {{{0.5, 0.5}, 0.0}, {{1.5, 1.5}, 0.0}};
  CHECK_THROWS_WITH_AS(planner.validate(prob, {}), "rovers[1]: start is on an obstacle", Error);
  prob.rovers[1].position = {9.0, 0.5};
  CHECK_THROWS_WITH_AS(planner.validate(prob, {}),
                       "rovers[1]: start (9, 0.5) m is outside the map (4 × 3 m)", Error);
  prob.rovers[1].position = {3.5, 2.5};
  CHECK_NOTHROW(planner.validate(prob, {}));
  CHECK_THROWS_AS(planner.validate(prob, {{"speed", 1.0}}), Error);
}

TEST_CASE("a planner run returns the documented metrics, tracks and curve") {
  PlannerRegistry reg = makeBuiltinRegistry();
  PlanningProblem prob;
  prob.world = coverage::generateWorld({});
  prob.rovers =
      coverage::cellsToStarts(prob.world.geometry(), coverage::randomStarts(prob.world, 2, 3));
  PlanResult r = reg.get("coverage").run(prob, {{"coverage", 0.9}}, nullptr, nullptr);
  for (const char* key : {"coverage", "moves", "makespan", "path_length_ratio", "distance_m",
                          "energy_j", "max_pitch_deg", "revisits", "unreachable_cells"})
    CHECK_NOTHROW(r.metric(key));
  CHECK(r.metric("coverage") >= 0.9);
  CHECK(r.stopReason == StopReason::GoalReached);
  REQUIRE(r.tracks.size() == 2);
  // Tracks start where the rovers were placed, in the local frame.
  CHECK(r.tracks[0].points.front().isApprox(prob.rovers[0].position));
  REQUIRE_FALSE(r.series.empty());
  CHECK(r.series[0].key == "coverage_vs_moves");
  CHECK(r.series[0].y.back() == doctest::Approx(r.metric("coverage")));
}
