// Planners describe themselves (core/planning/planner_specs.hpp): the ground they plan on, their
// starts, map defaults, memory estimates and metrics, so no caller needs their names.
#include <doctest/doctest.h>

#include <algorithm>

#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/coverage_memory.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/planning/planner.hpp"
#include "core/team/team_memory.hpp"
#include "core/team/team_specs.hpp"
#include "dem_literals.hpp"

using namespace rover;

namespace {

bool declares(const PlannerSpecs& specs, const std::string& key) {
  return std::any_of(specs.metrics.begin(), specs.metrics.end(), [&](const MetricInfo& m) { return m.key == key; });
}

// Every metric of the run is one the planner's description lists.
void checkDeclared(const Planner& planner, const PlanResult& r) {
  for (const auto& m : r.metrics) {
    INFO(planner.name() << " reports " << m.key);
    CHECK(declares(planner.specs(), m.key));
  }
  CHECK_FALSE(r.series.empty());
  const bool progress = std::any_of(r.series.begin(), r.series.end(),
                                    [&](const Series& s) { return s.key == planner.specs().progressSeries; });
  CHECK(progress);
}

}  // namespace

TEST_CASE("planner specs: each family names its ground, starts and progress") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const PlannerSpecs& coverage = reg.get("coverage").specs();
  CHECK(coverage.ground == Ground::CoverageGrid);
  CHECK(coverage.starts == StartPlacement::RandomCells);
  CHECK(coverage.progress == ProgressMeasure::Coverage);
  CHECK_FALSE(coverage.secondsPerRun);
  for (const char* name : {"team-search", "hybrid"}) {
    const PlannerSpecs& team = reg.get(name).specs();
    CHECK(team.ground == Ground::DemAndPdm);
    CHECK(team.starts == StartPlacement::Formation);
    CHECK(team.progress == ProgressMeasure::Detection);
    CHECK(team.secondsPerRun);
  }
  // The hybrid's legs cover their footprints: a stage team-search has not.
  CHECK(reg.get("hybrid").specs().stages.size() == reg.get("team-search").specs().stages.size());
  CHECK(reg.get("hybrid").specs().stages[2].doc != reg.get("team-search").specs().stages[2].doc);
}

TEST_CASE("planner specs: the coverage planner's metrics and curve are the ones it declares") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("coverage");
  PlanningProblem prob;
  prob.world = coverage::generateWorld({});
  prob.rovers = planner.defaultStarts(prob, {}, 2, 3);
  checkDeclared(planner, planner.run(prob, {{"coverage", 0.5}}, nullptr, nullptr));
  // Under localisation error it reports more: those are declared too.
  checkDeclared(planner, planner.run(prob, {{"coverage", 0.5}, {"odometry_noise", 5.0}}, nullptr, nullptr));
}

TEST_CASE("planner specs: a team mission's metrics and curve are the ones it declares") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("team-search");
  const auto dem = std::make_shared<const terrain::Dem>(test::demFrom(60, 60, 0.25, [](double, double) { return 0.0; }));
  PlanningProblem prob;
  prob.dem = dem;
  const ParamSet params{{"targets", std::int64_t{2}}, {"footprint_m", 5.0}};
  prob.rovers = planner.defaultStarts(prob, params, 2, 1);
  REQUIRE(prob.rovers.size() == 2);
  checkDeclared(planner, planner.run(prob, params, nullptr, nullptr));
}

TEST_CASE("planner specs: the ground on a map is the coverage grid at its cell, or the map itself") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const GridGeometry map{400, 400, 0.25, 0.25};
  const MapGround grid = reg.get("coverage").groundOnMap(map, {{"coverage_cell", 0.5}});
  CHECK(grid.kind == Ground::CoverageGrid);
  CHECK(grid.cell == 0.5);
  const MapGround own = reg.get("team-search").groundOnMap(map, {});
  CHECK(own.kind == Ground::DemAndPdm);
  // A cell the coverage grid cannot hold is refused by the same parameter's name.
  CHECK_THROWS_WITH_AS(reg.get("coverage").groundOnMap(map, {{"coverage_cell", 0.001}}),
                       doctest::Contains("coverage_cell"), Error);
}

TEST_CASE("planner specs: map defaults come from the planner that reads them") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const GridGeometry map{600, 600, 0.25, 0.25};
  const ParamSet coverage = reg.get("coverage").mapDefaults(map, terrain::Body::Mars);
  CHECK(std::get<double>(coverage.at("coverage_cell")) == coverage::defaultCoverageCell(map, coverage::CoverageParams{}.cellBudget));
  CHECK(std::get<double>(coverage.at("gravity")) == doctest::Approx(3.71));
  CHECK(reg.get("coverage").mapDefaults(map, terrain::Body::Unknown).count("gravity") == 0);
  CHECK(reg.get("team-search").mapDefaults(map, terrain::Body::Mars).empty());
}

TEST_CASE("planner specs: the memory estimate is the family's model, with the step budget it counts") {
  const PlannerRegistry reg = makeBuiltinRegistry();
  const GridGeometry map{600, 600, 0.25, 0.25};
  const Planner& cov = reg.get("coverage");
  ParamSet params{{"coverage_cell", 0.5}};
  const MemoryEstimate e = cov.memoryEstimate(map, cov.groundOnMap(map, params), 2, false, params);
  ParamSet none;
  const MemoryEstimate model = coverage::missionMemory(300 * 300, 0.5, 2, false, coverage::stepBudget(none, 0, 300 * 300, 2));
  CHECK(e.bytes == model.bytes);
  CHECK(e.what == model.what);
  // The budget the estimate counts is the one the run gets.
  CHECK(std::get<std::int64_t>(params.at("max_steps")) == coverage::kDefaultMovesPerCell * 300 * 300 / 2);
  CHECK(e.field == "params.coverage_cell");

  for (const char* name : {"team-search", "hybrid"}) {
    const Planner& team = reg.get(name);
    ParamSet tp{{"targets", std::int64_t{6}}};
    const MemoryEstimate t = team.memoryEstimate(map, team.groundOnMap(map, tp), 3, true, tp);
    CHECK(t.bytes == team::missionMemory(map.cellCount(), 3, true, tp, std::string(name) == "hybrid").bytes);
    CHECK(tp.size() == 1);  // nothing bounded
  }
}
