// rover::json: parameter values, descriptions and plan results as JSON, and parameter values read
// back from JSON with errors that name the key.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/common/params.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/planning/plan_result.hpp"
#include "server/json/plan_json.hpp"

using nlohmann::json;
using rover::ParamInfo;
using rover::ParamType;
using rover::ParamValue;
using rover::StopReason;

namespace {

ParamInfo info(const std::string& key, ParamType type) {
  ParamInfo i;
  i.key = key;
  i.type = type;
  return i;
}

// paramFromJson(i, v) must throw rover::Error{InvalidParameter} with field() == i.key.
void checkRejected(const ParamInfo& i, const json& v) {
  CAPTURE(i.key);
  CAPTURE(v.dump());
  bool threw = false;
  try {
    (void)rover::json::paramFromJson(i, v);
  } catch (const rover::Error& e) {
    threw = true;
    CHECK(e.code() == rover::ErrorCode::InvalidParameter);
    CHECK(e.field() == i.key);
    CHECK(std::string(e.what()).rfind(i.key + ": ", 0) == 0);
  }
  CHECK(threw);
}

}  // namespace

TEST_CASE("toJson(ParamValue) keeps each alternative's JSON type") {
  json b = rover::json::toJson(ParamValue{true});
  CHECK(b.is_boolean());
  CHECK(b.get<bool>() == true);
  CHECK(rover::json::toJson(ParamValue{false}) == json(false));

  json i = rover::json::toJson(ParamValue{std::int64_t{-42}});
  CHECK(i.is_number_integer());
  CHECK(i.get<std::int64_t>() == -42);

  json d = rover::json::toJson(ParamValue{2.5});
  CHECK(d.is_number_float());
  CHECK(d.get<double>() == doctest::Approx(2.5));
  // A whole double stays a float, so it reads back as a double.
  CHECK(rover::json::toJson(ParamValue{3.0}).is_number_float());

  json s = rover::json::toJson(ParamValue{std::string("spiral")});
  CHECK(s.is_string());
  CHECK(s.get<std::string>() == "spiral");

  json l = rover::json::toJson(ParamValue{std::vector<double>{1.0, 2.5, -3.0}});
  REQUIRE(l.is_array());
  REQUIRE(l.size() == 3);
  CHECK(l[0].get<double>() == doctest::Approx(1.0));
  CHECK(l[1].get<double>() == doctest::Approx(2.5));
  CHECK(l[2].get<double>() == doctest::Approx(-3.0));

  json empty = rover::json::toJson(ParamValue{std::vector<double>{}});
  CHECK(empty.is_array());
  CHECK(empty.empty());
}

TEST_CASE("toJson(ParamInfo) describes a parameter, with min, max and choices only when present") {
  ParamInfo r = info("coverage", ParamType::Real);
  r.defaultValue = 0.95;
  r.min = 0.01;
  r.max = 1.0;
  r.doc = "Coverage goal.";
  json jr = rover::json::toJson(r);
  CHECK(jr["key"] == "coverage");
  CHECK(jr["type"] == "real");
  CHECK(jr["default"].get<double>() == doctest::Approx(0.95));
  CHECK(jr["unit"] == "");
  CHECK(jr["doc"] == "Coverage goal.");
  CHECK(jr["min"].get<double>() == doctest::Approx(0.01));
  CHECK(jr["max"].get<double>() == doctest::Approx(1.0));
  CHECK_FALSE(jr.contains("choices"));

  // Half-open range: only the finite bound is written.
  ParamInfo n = info("max_steps", ParamType::Int);
  n.defaultValue = std::int64_t{0};
  n.min = 0;
  n.unit = "steps";
  json jn = rover::json::toJson(n);
  CHECK(jn["type"] == "int");
  CHECK(jn["unit"] == "steps");
  CHECK(jn["default"].is_number_integer());
  CHECK(jn["min"].get<double>() == doctest::Approx(0.0));
  CHECK_FALSE(jn.contains("max"));

  ParamInfo c = info("pattern", ParamType::Choice);
  c.defaultValue = std::string("spiral");
  c.choices = {"spiral", "boustrophedon", "custom"};
  json jc = rover::json::toJson(c);
  CHECK(jc["type"] == "choice");
  CHECK(jc["default"] == "spiral");
  CHECK(jc["choices"] == json({"spiral", "boustrophedon", "custom"}));
  CHECK_FALSE(jc.contains("min"));
  CHECK_FALSE(jc.contains("max"));

  ParamInfo f = info("frontier", ParamType::Bool);
  f.defaultValue = false;
  json jf = rover::json::toJson(f);
  CHECK(jf["type"] == "bool");
  CHECK(jf["default"] == false);

  ParamInfo l = info("cost_table", ParamType::RealList);
  l.defaultValue = std::vector<double>{};
  json jl = rover::json::toJson(l);
  CHECK(jl["type"] == "real_list");
  CHECK(jl["default"] == json::array());
}

TEST_CASE("toJson(infos) describes the whole coverage parameter table") {
  const std::vector<ParamInfo> infos = rover::coverage::coverageParamTable().infos();
  REQUIRE_FALSE(infos.empty());
  json arr = rover::json::toJson(infos);
  REQUIRE(arr.is_array());
  REQUIRE(arr.size() == infos.size());
  for (std::size_t k = 0; k < infos.size(); ++k) {
    CAPTURE(infos[k].key);
    CHECK(arr[k]["key"] == infos[k].key);
    CHECK(arr[k]["type"] == rover::paramTypeName(infos[k].type));
    CHECK(arr[k].contains("default"));
    CHECK(arr[k].contains("doc"));
    CHECK_FALSE(arr[k]["doc"].get<std::string>().empty());
    CHECK(arr[k].contains("choices") == (infos[k].type == ParamType::Choice));
    // Every JSON default reads back as the same value.
    CHECK(rover::json::paramFromJson(infos[k], arr[k]["default"]) == infos[k].defaultValue);
  }
  // Spot checks against the documented defaults.
  auto find = [&](const std::string& key) {
    for (const auto& j : arr)
      if (j["key"] == key) return j;
    return json();
  };
  CHECK(find("sense_radius")["default"] == 1);
  CHECK(find("sense_radius")["min"] == 1.0);
  CHECK(find("sense_radius")["max"] == 2.0);
  CHECK(find("mode")["default"] == "overlap");
  CHECK(find("pattern")["default"] == "spiral");
  CHECK(find("coverage")["default"].get<double>() == doctest::Approx(0.95));
  CHECK(find("rover_mass")["unit"] == "kg");
}

TEST_CASE("toJson(PlanResult): metrics object, units, rovers with [x, y] paths, series") {
  rover::PlanResult r;
  r.planner = "coverage";
  r.stopReason = StopReason::GoalReached;
  r.cancelled = false;
  r.metrics = {{"coverage", 0.96, ""}, {"moves", 120, "moves"}, {"distance_m", 130.5, "m"}};
  rover::Track t0;
  t0.rover = 0;
  t0.points = {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(1.5, 0.5), Eigen::Vector2d(1.5, 1.5)};
  t0.metrics = {{"moves", 2, "moves"}};
  rover::Track t1;
  t1.rover = 1;
  t1.points = {Eigen::Vector2d(-2.0, 3.25)};
  r.tracks = {t0, t1};
  r.series = {{"coverage_vs_moves", "moves", "coverage", {0, 1, 2}, {0.1, 0.2, 0.3}}};

  json j = rover::json::toJson(r);
  CHECK(j["planner"] == "coverage");
  CHECK(j["stop_reason"] == "goal_reached");
  CHECK(j["cancelled"] == false);

  REQUIRE(j["metrics"].is_object());
  CHECK(j["metrics"].size() == 3);
  CHECK(j["metrics"]["coverage"].get<double>() == doctest::Approx(0.96));
  CHECK(j["metrics"]["moves"].get<double>() == doctest::Approx(120));
  CHECK(j["metrics"]["distance_m"].get<double>() == doctest::Approx(130.5));

  // Only metrics with a unit appear in metric_units.
  REQUIRE(j["metric_units"].is_object());
  CHECK(j["metric_units"].size() == 2);
  CHECK(j["metric_units"]["moves"] == "moves");
  CHECK(j["metric_units"]["distance_m"] == "m");
  CHECK_FALSE(j["metric_units"].contains("coverage"));

  REQUIRE(j["rovers"].is_array());
  REQUIRE(j["rovers"].size() == 2);
  const json& r0 = j["rovers"][0];
  CHECK(r0["rover"] == 0);
  CHECK(r0["metrics"]["moves"].get<double>() == doctest::Approx(2));
  REQUIRE(r0["path"].is_array());
  REQUIRE(r0["path"].size() == 3);
  for (const auto& p : r0["path"]) {
    REQUIRE(p.is_array());
    CHECK(p.size() == 2);
  }
  CHECK(r0["path"][0][0].get<double>() == doctest::Approx(0.5));
  CHECK(r0["path"][0][1].get<double>() == doctest::Approx(0.5));
  CHECK(r0["path"][1][0].get<double>() == doctest::Approx(1.5));
  CHECK(r0["path"][1][1].get<double>() == doctest::Approx(0.5));
  CHECK(r0["path"][2][1].get<double>() == doctest::Approx(1.5));
  const json& r1 = j["rovers"][1];
  CHECK(r1["rover"] == 1);
  CHECK(r1["metrics"].is_object());
  CHECK(r1["metrics"].empty());
  REQUIRE(r1["path"].size() == 1);
  CHECK(r1["path"][0][0].get<double>() == doctest::Approx(-2.0));
  CHECK(r1["path"][0][1].get<double>() == doctest::Approx(3.25));

  REQUIRE(j["series"].is_object());
  REQUIRE(j["series"].contains("coverage_vs_moves"));
  const json& s = j["series"]["coverage_vs_moves"];
  CHECK(s["x_label"] == "moves");
  CHECK(s["y_label"] == "coverage");
  REQUIRE(s["x"].size() == 3);
  REQUIRE(s["y"].size() == 3);
  CHECK(s["x"][2].get<double>() == doctest::Approx(2));
  CHECK(s["y"][2].get<double>() == doctest::Approx(0.3));

  // The whole thing serialises and parses back unchanged.
  CHECK(json::parse(j.dump()) == j);
}

TEST_CASE("toJson(PlanResult) of an empty result has empty containers, not nulls") {
  rover::PlanResult r;
  r.planner = "x";
  r.stopReason = StopReason::Cancelled;
  r.cancelled = true;
  json j = rover::json::toJson(r);
  CHECK(j["cancelled"] == true);
  CHECK(j["metrics"].is_object());
  CHECK(j["metrics"].empty());
  CHECK(j["metric_units"].is_object());
  CHECK(j["rovers"].is_array());
  CHECK(j["rovers"].empty());
  CHECK(j["series"].is_object());
  CHECK(j["series"].empty());
}

TEST_CASE("paramFromJson: Bool") {
  const ParamInfo i = info("frontier", ParamType::Bool);
  CHECK(rover::json::paramFromJson(i, json(true)) == ParamValue{true});
  CHECK(rover::json::paramFromJson(i, json(false)) == ParamValue{false});
  checkRejected(i, json(1));
  checkRejected(i, json(0));
  checkRejected(i, json("true"));
  checkRejected(i, json(nullptr));
  checkRejected(i, json::array({true}));
}

TEST_CASE("paramFromJson: Int") {
  const ParamInfo i = info("sense_radius", ParamType::Int);
  ParamValue v = rover::json::paramFromJson(i, json(2));
  REQUIRE(std::holds_alternative<std::int64_t>(v));
  CHECK(std::get<std::int64_t>(v) == 2);
  ParamValue neg = rover::json::paramFromJson(i, json(-7));
  CHECK(std::get<std::int64_t>(neg) == -7);
  // A float is passed on as a double: 3.0 is accepted later, 3.5 rejected by paramAsInt.
  ParamValue f = rover::json::paramFromJson(i, json::parse("3.0"));
  REQUIRE(std::holds_alternative<double>(f));
  CHECK(std::get<double>(f) == doctest::Approx(3.0));
  ParamInfo ranged = i;
  ranged.min = 1;
  ranged.max = 5;
  CHECK(rover::paramAsInt(ranged, f) == 3);
  CHECK_THROWS_AS(rover::paramAsInt(ranged, rover::json::paramFromJson(i, json(3.5))),
                  rover::Error);

  checkRejected(i, json("2"));
  checkRejected(i, json(true));
  checkRejected(i, json(nullptr));
  checkRejected(i, json::array({2}));
  checkRejected(i, json::object({{"value", 2}}));
}

TEST_CASE("paramFromJson: Real") {
  const ParamInfo i = info("coverage", ParamType::Real);
  ParamValue d = rover::json::paramFromJson(i, json(0.9));
  REQUIRE(std::holds_alternative<double>(d));
  CHECK(std::get<double>(d) == doctest::Approx(0.9));
  // An integer literal is accepted for a real parameter.
  ParamValue n = rover::json::paramFromJson(i, json(1));
  REQUIRE(std::holds_alternative<std::int64_t>(n));
  CHECK(rover::paramAsReal(i, n) == doctest::Approx(1.0));

  checkRejected(i, json("0.9"));
  checkRejected(i, json(false));
  checkRejected(i, json(nullptr));
  checkRejected(i, json::array({0.9}));
}

TEST_CASE("paramFromJson: Choice") {
  ParamInfo i = info("pattern", ParamType::Choice);
  i.choices = {"spiral", "boustrophedon", "custom"};
  ParamValue v = rover::json::paramFromJson(i, json("boustrophedon"));
  REQUIRE(std::holds_alternative<std::string>(v));
  CHECK(std::get<std::string>(v) == "boustrophedon");
  // Membership is checked later, by paramAsChoice, with the same field.
  ParamValue other = rover::json::paramFromJson(i, json("zigzag"));
  try {
    (void)rover::paramAsChoice(i, other);
    FAIL("paramAsChoice accepted 'zigzag'");
  } catch (const rover::Error& e) {
    CHECK(e.code() == rover::ErrorCode::InvalidParameter);
    CHECK(e.field() == "pattern");
  }

  checkRejected(i, json(0));
  checkRejected(i, json(true));
  checkRejected(i, json(nullptr));
  checkRejected(i, json::array({"spiral"}));
}

TEST_CASE("paramFromJson: RealList") {
  const ParamInfo i = info("cost_table", ParamType::RealList);
  ParamValue v = rover::json::paramFromJson(i, json::parse("[1, 2.5, -3]"));
  REQUIRE(std::holds_alternative<std::vector<double>>(v));
  const auto& l = std::get<std::vector<double>>(v);
  REQUIRE(l.size() == 3);
  CHECK(l[0] == doctest::Approx(1.0));
  CHECK(l[1] == doctest::Approx(2.5));
  CHECK(l[2] == doctest::Approx(-3.0));
  ParamValue e = rover::json::paramFromJson(i, json::array());
  CHECK(std::get<std::vector<double>>(e).empty());

  checkRejected(i, json("1,2,3"));
  checkRejected(i, json(1.0));
  checkRejected(i, json(nullptr));
  checkRejected(i, json::object());
  checkRejected(i, json::parse("[1, \"2\", 3]"));
  checkRejected(i, json::parse("[1, null]"));
  checkRejected(i, json::parse("[true]"));
  checkRejected(i, json::parse("[[1, 2]]"));
}

TEST_CASE("paramFromJson then the table: a parsed coverage parameter set") {
  const auto infos = rover::coverage::coverageParamTable().infos();
  json body = json::parse(R"({"pattern": "boustrophedon", "sense_radius": 2, "frontier": true,
                              "coverage": 0.8, "beta": 0.25, "alpha": 0.75})");
  rover::ParamSet set;
  for (const auto& i : infos)
    if (body.contains(i.key)) set[i.key] = rover::json::paramFromJson(i, body[i.key]);
  CHECK(set.size() == body.size());
  rover::coverage::CoverageParams p = rover::coverage::parseCoverageParams(set);
  CHECK(p.pattern == "boustrophedon");
  CHECK(p.senseRadius == 2);
  CHECK(p.frontier);
  CHECK(p.coverage == doctest::Approx(0.8));
  CHECK(p.alpha == doctest::Approx(0.75));
  CHECK(p.beta == doctest::Approx(0.25));
}

TEST_CASE("integers beyond int64 are rejected for Int and read as reals for Real") {
  rover::ParamInfo i;
  i.key = "max_steps";
  i.type = rover::ParamType::Int;
  auto big = nlohmann::json::parse("18446744073709551615");
  CHECK_THROWS_WITH_AS(rover::json::paramFromJson(i, big), "max_steps: is out of range",
                       rover::Error);
  i.type = rover::ParamType::Real;
  auto v = rover::json::paramFromJson(i, big);
  CHECK(std::get<double>(v) == doctest::Approx(1.8446744073709552e19));
}
