#include <doctest/doctest.h>

#include "core/coverage/coverage_params.hpp"
#include "core/planning/planner.hpp"
#include "core/team/team_entry.hpp"

#include <algorithm>
#include <cmath>

using namespace rover;
using namespace rover::coverage;

namespace {
Error errorOf(const ParamSet& s) {
  try {
    parseCoverageParams(s);
  } catch (const Error& e) {
    return e;
  }
  FAIL("no error thrown");
  return Error(ErrorCode::InvalidInput, "", "");
}
}  // namespace

TEST_CASE("defaults are the documented ones (SPEC §1)") {
  CoverageParams p = parseCoverageParams({});
  CHECK(p.mode == TeamMode::Overlap);
  CHECK(p.pattern == "spiral");
  CHECK(p.senseRadius == 1);
  CHECK(p.coverage == 0.95);
  CHECK(p.alpha == 1.0);
  CHECK(p.beta == 0.0);
  CHECK(p.mcVisited == 1.1);
  CHECK(p.stepBudget(3600) == 72000);
  CHECK(p.energy.massKg == 7.0);
  CHECK(p.energy.gravity == 1.62);
  auto infos = coverageParamTable().infos();
  for (const auto& i : infos) CHECK_MESSAGE(!i.doc.empty(), i.key);
}

TEST_CASE("values are typed, ranged and named") {
  CoverageParams p = parseCoverageParams({{"sense_radius", std::int64_t{2}},
                                          {"coverage", 0.99},
                                          {"mode", std::string("voronoi")},
                                          {"frontier", true},
                                          {"max_steps", 3.0}});
  CHECK(p.senseRadius == 2);
  CHECK(p.coverage == 0.99);
  CHECK(p.mode == TeamMode::Voronoi);
  CHECK(p.frontier);
  CHECK(p.maxSteps == 3);

  Error e = errorOf({{"sense_radius", std::int64_t{3}}});
  CHECK(e.code() == ErrorCode::InvalidParameter);
  CHECK(e.field() == "sense_radius");
  CHECK(std::string(e.what()) == "sense_radius: must be in [1, 2], got 3");

  CHECK(errorOf({{"max_steps", 2.5}}).field() == "max_steps");
  CHECK(errorOf({{"coverage", 0.0}}).field() == "coverage");
  CHECK(errorOf({{"coverage", std::string("all")}}).field() == "coverage");
  CHECK(errorOf({{"frontier", std::int64_t{1}}}).field() == "frontier");
  CHECK(errorOf({{"mc_visited", 1.0}}).field() == "mc_visited");  // paper 000: >= 1.1
  // The rejected value as sent, not rounded to six digits ("got 1.1" would contradict the range).
  CHECK(std::string(errorOf({{"mc_visited", 1.0999999999}}).what()) ==
        "mc_visited: must be in [1.1, 1000], got 1.0999999999");
  CHECK(std::string(errorOf({{"coverage", 1e300}}).what()).ends_with("got 1e+300"));
  CHECK(errorOf({{"pattern", std::string("zigzag")}}).field() == "pattern");
}

TEST_CASE("unknown keys are rejected with their name") {
  Error e = errorOf({{"sensing", std::int64_t{1}}});
  CHECK(e.code() == ErrorCode::UnknownParameter);
  CHECK(e.field() == "sensing");
}

TEST_CASE("alpha + beta must be 1 (paper 000 eq. 3)") {
  CHECK_NOTHROW(parseCoverageParams({{"alpha", 0.3}, {"beta", 0.7}}));
  Error e = errorOf({{"alpha", 0.5}, {"beta", 0.2}});
  CHECK(e.field() == "beta");
}

TEST_CASE("a custom cost table needs pattern custom and the right shape") {
  CHECK_NOTHROW(parseCoverageParams(
      {{"pattern", std::string("custom")},
       {"cost_table", std::vector<double>{0.2, 0.4, 0.1, 0.7, 0.9, 0.8, 0.6, 0.5}}}));
  CHECK(errorOf({{"pattern", std::string("custom")}}).field() == "cost_table");
  CHECK(errorOf({{"cost_table", std::vector<double>{0.2, 0.4, 0.1, 0.7, 0.9, 0.8, 0.6, 0.5}}})
            .field() == "cost_table");
}

TEST_CASE("every planner's table sorts its parameters into sections, a few common, and its presets parse") {
  const PlannerRegistry registry = makeBuiltinRegistry();
  for (const auto& name : registry.names()) {
    const Planner& p = registry.get(name);
    CAPTURE(name);
    int common = 0;
    std::vector<std::string> groups;
    for (const auto& info : p.params()) {
      CHECK(!info.group.empty());
      common += info.level == ParamLevel::Common;
      // A section is contiguous in the table, so a form can show it in one piece.
      if (groups.empty() || groups.back() != info.group) {
        CHECK_MESSAGE(std::find(groups.begin(), groups.end(), info.group) == groups.end(), info.group);
        groups.push_back(info.group);
      }
    }
    CHECK(common >= 5);
    CHECK(common * 2 < static_cast<int>(p.params().size()));
    REQUIRE(p.presets().size() == 2);
    for (const auto& preset : p.presets()) {
      CHECK(!preset.doc.empty());
      // Through the planner's parser, cross-field checks (alpha + beta = 1, ...) included.
      if (name == "coverage") CHECK_NOTHROW(parseCoverageParams(preset.values));
      else CHECK_NOTHROW(team::parseTeamParams(preset.values));
    }
  }
  const auto team = registry.get("team-search").presets();
  CHECK(team[0].name == "paper 001");
  CHECK(std::get<std::int64_t>(team[0].values.at("max_vertices")) == 1250);
  CHECK(std::get<std::string>(team[0].values.at("coordination")) == "paper");
  CHECK(registry.get("coverage").presets()[0].name == "paper 002");
}

TEST_CASE("an integer parameter written as a float is read exactly up to its documented maximum") {
  // The seed's documented range is [0, 9e18]; a client that writes 9e18 (a JSON float) means the
  // integer 9 000 000 000 000 000 000, which a double holds exactly (issue 22).
  const ParamInfo seed = intParam("seed", 0, 9.0e18, "", "");
  CHECK(paramAsInt(seed, ParamValue{9.0e18}) == 9000000000000000000LL);
  CHECK(paramAsInt(seed, ParamValue{std::int64_t{9000000000000000000LL}}) == 9000000000000000000LL);
  CHECK(paramAsInt(seed, ParamValue{4.0e15}) == 4000000000000000LL);
  CHECK_THROWS_AS(paramAsInt(seed, ParamValue{9.1e18}), Error);        // over the range
  CHECK_THROWS_AS(paramAsInt(seed, ParamValue{1.0e19}), Error);        // over int64: never converted
  CHECK_THROWS_AS(paramAsInt(seed, ParamValue{3.5}), Error);           // not whole
  CHECK_THROWS_AS(paramAsInt(seed, ParamValue{std::nan("")}), Error);  // not a number
}
