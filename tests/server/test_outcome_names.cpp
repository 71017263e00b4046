// The outcome names: each table names every value once and reads back, the page's module
// (web/js/outcomes.js) and the OpenAPI document carry the same lists in the same order, and a
// mission row keeps every status.
#include <doctest/doctest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/planning/outcomes.hpp"
#include "core/team/coordination.hpp"
#include "core/team/route_generator.hpp"
#include "server/store/database.hpp"
#include "server/store/run_status.hpp"
#include "api_server.hpp"

using namespace rover;
using nlohmann::json;

namespace {

// Every value once, every name once, and name → value → name is the identity.
template <NamedEnum E>
void checkTable() {
  std::set<int> values;
  std::set<std::string_view> names;
  for (const auto& [value, name] : EnumNames<E>::table) {
    const std::string_view shown = name;  // clang 14 cannot capture a structured binding
    CAPTURE(shown);
    CHECK(values.insert(static_cast<int>(value)).second);
    CHECK(names.insert(name).second);
    CHECK(!name.empty());
    CHECK(name.find('\'') == std::string_view::npos);  // database.cpp quotes them into SQL
    CHECK(enumName(value) == name);
    REQUIRE(parseEnum<E>(name).has_value());
    CHECK(*parseEnum<E>(name) == value);
  }
  // Values are numbered from 0 without gaps, so a full table has one entry per value.
  CHECK(*values.rbegin() == static_cast<int>(values.size()) - 1);
  CHECK(!parseEnum<E>("").has_value());
  CHECK(!parseEnum<E>("no such name").has_value());
}

// The quoted values of `export const NAME = Object.freeze({ ... });` in the page's module.
std::vector<std::string> jsList(const std::string& js, const std::string& name) {
  const std::regex block("export const " + name + R"( = Object\.freeze\(\{([^}]*)\}\);)");
  std::smatch m;
  REQUIRE_MESSAGE(std::regex_search(js, m, block), "web/js/outcomes.js has no " << name);
  const std::string body = m[1].str();
  const std::regex value(R"(:\s*'([^']*)')");
  std::vector<std::string> out;
  for (auto it = std::sregex_iterator(body.begin(), body.end(), value); it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1].str());
  return out;
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "cannot read " << path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("outcome names: every table names each value once and reads back") {
  checkTable<RunStatus>();
  checkTable<StopReason>();
  checkTable<IncidentKind>();
  checkTable<TargetStatus>();
  checkTable<team::PathStatus>();
  checkTable<team::SimStatus>();
  checkTable<team::RouteMethod>();
  checkTable<team::CoordinationMode>();
}

TEST_CASE("outcome names: a run is over in every status but queued and running") {
  for (const auto& [s, name] : EnumNames<RunStatus>::table) {
    const std::string_view shown = name;  // clang 14 cannot capture a structured binding
    CAPTURE(shown);
    CHECK(isFinal(s) == (s != RunStatus::Queued && s != RunStatus::Running));
  }
  // A study's statuses are a subset of the missions', with the same "is it over" rule.
  CHECK(!isFinal(kStudyStatuses[0]));
  CHECK(!isFinal(kStudyStatuses[1]));
  for (std::size_t i = 2; i < kStudyStatuses.size(); ++i) CHECK(isFinal(kStudyStatuses[i]));
}

TEST_CASE("outcome names: the page's module lists the server's names in the same order") {
  const std::string js = readText(std::string(ROVER_SOURCE_DIR) + "/web/js/outcomes.js");
  CHECK(jsList(js, "RunStatus") == enumNames<RunStatus>());
  CHECK(jsList(js, "StopReason") == enumNames<StopReason>());
  CHECK(jsList(js, "IncidentKind") == enumNames<IncidentKind>());
  CHECK(jsList(js, "TargetStatus") == enumNames<TargetStatus>());
}

TEST_CASE("outcome names: OpenAPI publishes the tables as enums") {
  test::TempDir tmp;
  test::ApiServer s(tmp.str("data"));
  const json doc = s.get("/api/openapi.json").json();
  const json& schemas = doc["components"]["schemas"];
  CHECK(schemas["Mission"]["properties"]["status"]["enum"] == json(enumNames<RunStatus>()));
  json study = json::array();
  for (RunStatus st : kStudyStatuses) study.push_back(enumName(st));
  CHECK(schemas["Study"]["properties"]["status"]["enum"] == study);
  const json& result = schemas["PlanResult"]["properties"];
  CHECK(result["stop_reason"]["enum"] == json(enumNames<StopReason>()));
  CHECK(result["incidents"]["items"]["properties"]["kind"]["enum"] == json(enumNames<IncidentKind>()));
  CHECK(result["targets"]["items"]["properties"]["status"]["enum"] == json(enumNames<TargetStatus>()));
}

TEST_CASE("outcome names: the database stores every status and reads it back") {
  store::Database db(":memory:");
  db.insertMap({"map", "a map", "2026-01-01T00:00:00.000Z", json::object()});
  store::MissionRecord m;
  m.id = "m";
  m.mapId = "map";
  m.planner = "coverage";
  m.spec = json::object();
  m.createdAt = "2026-01-01T00:00:00.000Z";
  db.insertMission(m);
  for (const auto& [status, name] : EnumNames<RunStatus>::table) {
    const std::string_view shown = name;  // clang 14 cannot capture a structured binding
    CAPTURE(shown);
    db.updateMission("m", status, "");
    CHECK(db.getMission("m")->status == status);
  }
}
