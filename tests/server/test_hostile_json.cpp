// Hostile and careless clients at the JSON / API edge (issue 14): nesting and size limits before
// any DOM, absurd numbers, non-string and over-long names, pagination bounds, the map-body cache
// against a racing delete, and every error naming its field. Over loopback, bounded loops only.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <set>
#include <thread>

#include "api_server.hpp"
#include "core/pdm/pdm.hpp"
#include "maps/dem_io.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/pdm_json.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::errorField;
using rover::test::request;
using rover::test::TempDir;
using Json = nlohmann::json;
namespace rj = rover::json;

namespace {

std::string nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

// The error an expression throws, as (status, code, field).
struct Thrown {
  int status = 0;
  std::string code, field;
};
template <class F>
Thrown apiErrorOf(F&& f) {
  try {
    f();
  } catch (const http::ApiError& e) {
    return {e.status(), e.code(), e.field()};
  }
  return {};
}

Json mission(const std::string& map, const std::string& planner = "coverage") {
  return {{"map", map}, {"planner", planner}, {"rovers", {{{"x", 10.5}, {"y", 10.5}, {"heading", 0}}}},
          {"params", Json::object()}};
}

}  // namespace

// ---- the edge parser ---------------------------------------------------------------------------

TEST_CASE("json edge: nesting depth is counted outside strings, before any DOM") {
  CHECK(rj::jsonNestingDepth("{}", 64) == 1);
  CHECK(rj::jsonNestingDepth(R"({"a":[{"b":[1]}]})", 64) == 4);
  CHECK(rj::jsonNestingDepth(R"({"a":"[[[[{{{{"})", 64) == 1);
  CHECK(rj::jsonNestingDepth(R"({"a":"\"[[[[","b":[]})", 64) == 2);  // escaped quote stays in the string
  // The scan stops once past the limit, so a huge input costs no more than its prefix.
  CHECK(rj::jsonNestingDepth(nested(70'000), 64) == 65);
}

TEST_CASE("json edge: 70 000-deep, too large, not JSON, not an object") {
  const rj::JsonLimits limits{1024, 64};
  auto deep = apiErrorOf([&] { rj::parseJsonLimited("{\"a\":" + nested(70'000) + "}", rj::kMissionJsonLimits); });
  CHECK(deep.status == 400);
  CHECK(deep.code == "too_deep");
  CHECK(deep.field == "body");
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("{\"a\":" + nested(63) + "}", limits); }).status == 0);
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("{\"a\":" + nested(64) + "}", limits); }).code == "too_deep");
  auto big = apiErrorOf([&] { rj::parseJsonLimited("{\"a\":\"" + std::string(2000, 'x') + "\"}", limits); });
  CHECK(big.status == 413);
  CHECK(big.field == "body");
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("{\"a\":", limits); }).code == "bad_json");
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("[1,2]", limits); }).code == "bad_json");
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("[1,2]", limits, false); }).status == 0);
  CHECK(apiErrorOf([&] { rj::parseJsonLimited("{\"x\":1e400}", limits); }).code == "bad_json");
}

TEST_CASE("json edge: names are UTF-8 text of at most 200 characters") {
  CHECK(apiErrorOf([] { rj::checkName(std::string(200, 'n'), "name"); }).status == 0);
  CHECK(apiErrorOf([] {
          std::string accents;
          for (int i = 0; i < 200; ++i) accents += "\xC3\xA9";  // é: 200 characters, 400 bytes
          rj::checkName(accents, "name");
        }).status == 0);
  auto longName = apiErrorOf([] { rj::checkName(std::string(201, 'n'), "name"); });
  CHECK(longName.status == 400);
  CHECK(longName.field == "name");
  CHECK(apiErrorOf([] { rj::checkName("bad \xC3\x28 utf8", "name"); }).field == "name");
  CHECK(apiErrorOf([] { rj::checkName("\xED\xA0\x80", "name"); }).field == "name");  // a surrogate
  CHECK(apiErrorOf([] { rj::checkName(std::string("a\0b", 3), "name"); }).field == "name");  // NUL
  CHECK(apiErrorOf([] { rj::checkName("tab\there", "name"); }).field == "name");
  CHECK(apiErrorOf([] { rj::checkName("\xC0\xAF", "name"); }).field == "name");      // overlong '/'
}

// ---- the pure mission-request parser -----------------------------------------------------------

TEST_CASE("mission request: a minimal request parses for every registered planner") {
  const PlannerRegistry planners = makeBuiltinRegistry();
  for (const auto& name : planners.names()) {
    CAPTURE(name);
    Json body = mission("m1", name);
    body["name"] = "run";
    body["pace"] = 5;
    auto r = rj::parseMissionRequest(body, planners);
    CHECK(r.mapId == "m1");
    CHECK(r.planner == name);
    CHECK(r.name == "run");
    REQUIRE(r.rovers.size() == 1);
    CHECK(r.rovers[0].position.x() == 10.5);
    CHECK(r.pace.value() == 5);
    CHECK_FALSE(r.spec.contains("map"));
    CHECK(r.spec["name"] == "run");
  }
}

TEST_CASE("mission request: every number outside its table range is refused with its field") {
  const PlannerRegistry planners = makeBuiltinRegistry();
  int checked = 0;
  for (const auto& name : planners.names()) {
    for (const auto& info : planners.get(name).params()) {
      if (info.type != ParamType::Int && info.type != ParamType::Real) continue;
      for (double bad : {1e300, -1e300, info.max + std::max(1.0, std::fabs(info.max)), info.min - 1.0}) {
        if (!std::isfinite(bad) || (bad >= info.min && bad <= info.max)) continue;
        Json body = mission("m1", name);
        body["params"][info.key] = bad;
        CAPTURE(name);
        CAPTURE(info.key);
        CAPTURE(bad);
        auto e = apiErrorOf([&] { rj::parseMissionRequest(body, planners); });
        CHECK(e.status == 400);
        CHECK(e.field == "params." + info.key);
        ++checked;
      }
    }
  }
  CHECK(checked > 50);
}

TEST_CASE("mission request: absurd rovers, pace, names and shapes name their field") {
  const PlannerRegistry planners = makeBuiltinRegistry();
  auto fieldOf = [&](const Json& body) { return apiErrorOf([&] { rj::parseMissionRequest(body, planners); }).field; };
  Json b = mission("m1");
  b["rovers"][0]["x"] = 1e300;
  CHECK(fieldOf(b) == "rovers[0].x");
  b = mission("m1");
  b["rovers"][0]["y"] = -1e30;
  CHECK(fieldOf(b) == "rovers[0].y");
  b = mission("m1");
  b["rovers"][0]["heading"] = 1e300;
  CHECK(fieldOf(b) == "rovers[0].heading");
  b = mission("m1");
  b["rovers"][0]["heading"] = "north";
  CHECK(fieldOf(b) == "rovers[0].heading");
  b = mission("m1");
  b["pace"] = 1e300;
  CHECK(fieldOf(b) == "pace");
  b = mission("m1");
  b["name"] = Json::array({1, 2});
  CHECK(fieldOf(b) == "name");
  b = mission("m1");
  b["name"] = std::string(201, 'n');
  CHECK(fieldOf(b) == "name");
  b = mission("m1");
  b["map"] = 7;
  CHECK(fieldOf(b) == "map");
  b = mission("m1");
  b["rovers"] = Json::array();
  for (int i = 0; i < 65; ++i) b["rovers"].push_back({{"x", 1}, {"y", 1}});
  CHECK(fieldOf(b) == "rovers");
  b = mission("m1");
  b["params"] = {{"max_steps", 1e300}};
  CHECK(fieldOf(b) == "params.max_steps");
  b = mission("m1");
  b["params"] = {{"cost_table", Json::array({1, "x"})}};
  CHECK(fieldOf(b) == "params.cost_table");
  b = mission("m1");
  b["planner"] = "warp";
  CHECK(fieldOf(b) == "planner");
  b = mission("m1");
  b[std::string(5000, 'k')] = 1;
  CHECK(fieldOf(b).size() < 100);  // the unknown key is named, cut short
}

TEST_CASE("PDM JSON: more than 256 components, non-finite or extreme values name their field") {
  auto fieldOf = [](const Json& j) {
    try {
      auto cs = rj::gaussiansFromJson(j);
      pdm::validateGaussians(cs, GridGeometry{600, 600, 0.25, 0.25});
    } catch (const Error& e) {
      return e.field();
    }
    return std::string();
  };
  Json many = {{"components", Json::array()}};
  for (int i = 0; i < 257; ++i) many["components"].push_back({{"x", 1}, {"y", 1}, {"sigma_x", 1}});
  CHECK(fieldOf(many) == "components");
  auto one = [](const Json& c) {
    Json body = {{"components", Json::array()}};
    body["components"].push_back({{"x", 75}, {"y", 75}, {"sigma_x", 5}});
    body["components"].push_back(c);
    return body;
  };
  CHECK(fieldOf(one({{"x", 75}, {"y", 1e30}, {"sigma_x", 5}})) == "components[1].y");
  CHECK(fieldOf(one({{"x", -1e30}, {"y", 1}, {"sigma_x", 5}})) == "components[1].x");
  CHECK(fieldOf(one({{"x", 75}, {"y", 75}, {"sigma_x", 1e-300}})) == "components[1].sigma_x");
  CHECK(fieldOf(one({{"x", 75}, {"y", 75}, {"sigma_x", 5}, {"sigma_y", 1e300}})) == "components[1].sigma_y");
  CHECK(fieldOf(one({{"x", 75}, {"y", 75}, {"sigma_x", 5}, {"rotation_deg", 1e300}})) == "components[1].rotation_deg");
  CHECK(fieldOf(one({{"x", 75}, {"y", 75}, {"sigma_x", 5}, {"weight", 1e300}})) == "components[1].weight");
  CHECK(fieldOf(one({{"x", 75}, {"y", 75}, {"sigma_x", 5}, {"sigma_y", 0.01}, {"rotation_deg", 33}})).empty());
}

// ---- over loopback -----------------------------------------------------------------------------

TEST_CASE("hostile: a 70 000-deep mission body is refused and the server goes on") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  for (int depth : {50'000, 70'000}) {
    Json body = mission(map);
    std::string text = body.dump();
    text.insert(text.size() - 1, ",\"name\":" + nested(depth));
    CAPTURE(depth);
    checkError(s.post("/api/missions", text), 400, "too_deep", "body");
  }
  CHECK(s.get("/api/health").status == 200);
  // A deep PDM body too.
  checkError(s.post("/api/maps/" + map + "/pdms", "{\"components\":" + nested(70'000) + "}"), 400, "too_deep", "body");
  CHECK(s.get("/api/health").status == 200);
  CHECK(s.get("/api/missions").json().empty());
}

TEST_CASE("hostile: absurd numbers and names over HTTP, every error naming its field") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  const std::string pdms = "/api/maps/" + map + "/pdms";
  auto pdmBody = [](Json c) { return Json{{"name", "p"}, {"components", Json::array({c})}}.dump(); };
  struct Case {
    std::string what;
    test::HttpResult r;
    int status;
    std::string field;
  };
  std::vector<Case> cases;
  cases.push_back({"max=1e300", s.get("/api/maps/" + map + "/layers/elevation.png?max=1e300"), 400, "max"});
  cases.push_back({"max=-5", s.get("/api/maps/" + map + "/layers/elevation.png?max=-5"), 400, "max"});
  cases.push_back({"max=2.5", s.get("/api/maps/" + map + "/layers/elevation.png?max=2.5"), 400, "max"});
  cases.push_back({"pdm name 5", s.post(pdms, R"({"name":5,"components":[{"x":75,"y":75,"sigma_x":10}]})"), 400, "name"});
  cases.push_back({"pdm name long", s.post(pdms, Json{{"name", std::string(201, 'n')}, {"random", 2}}.dump()), 400, "name"});
  cases.push_back({"pdm y 1e30", s.post(pdms, pdmBody({{"x", 75}, {"y", 1e30}, {"sigma_x", 10}})), 400, "components[0].y"});
  cases.push_back({"pdm sigma 1e-300", s.post(pdms, pdmBody({{"x", 75}, {"y", 75}, {"sigma_x", 1e-300}})), 400, "components[0].sigma_x"});
  cases.push_back({"pdm sigma 1e300", s.post(pdms, pdmBody({{"x", 75}, {"y", 75}, {"sigma_x", 3}, {"sigma_y", 1e300}})), 400, "components[0].sigma_y"});
  cases.push_back({"pdm weight -1", s.post(pdms, pdmBody({{"x", 75}, {"y", 75}, {"sigma_x", 3}, {"weight", -1}})), 400, "components[0].weight"});
  cases.push_back({"pdm no components", s.post(pdms, R"({"name":"x"})"), 400, "components"});
  cases.push_back({"pdm components object", s.post(pdms, R"({"components":{"x":1}})"), 400, "components"});
  cases.push_back({"pdm random 1e300", s.post(pdms, R"({"random":1e300})"), 400, "random"});
  cases.push_back({"pdm not json", s.post(pdms, "{nope"), 400, "body"});
  cases.push_back({"pdm array", s.post(pdms, "[1]"), 400, "body"});
  cases.push_back({"pdm off the map", s.post(pdms, pdmBody({{"x", 75}, {"y", 300}, {"sigma_x", 0.5}})), 400, "components"});
  Json m = mission(map);
  m["name"] = 42;
  cases.push_back({"mission name 42", s.post("/api/missions", m.dump()), 400, "name"});
  m = mission(map);
  m["rovers"][0]["heading"] = 1e300;
  cases.push_back({"mission heading 1e300", s.post("/api/missions", m.dump()), 400, "rovers[0].heading"});
  m = mission(map);
  m["rovers"][0]["x"] = 1e300;
  cases.push_back({"mission x 1e300", s.post("/api/missions", m.dump()), 400, "rovers[0].x"});
  m = mission(map);
  m["params"]["coverage_cell"] = 1e300;
  cases.push_back({"mission coverage_cell", s.post("/api/missions", m.dump()), 400, "params.coverage_cell"});
  m = mission(map);
  m["pace"] = -1;
  cases.push_back({"mission pace", s.post("/api/missions", m.dump()), 400, "pace"});
  m = mission(map);
  m["rovers"][0]["x"] = 1e6;  // finite but off the map: the planner's own check
  cases.push_back({"mission off the map", s.post("/api/missions", m.dump()), 400, "rovers[0]"});
  cases.push_back({"mission big", s.post("/api/missions", Json{{"name", std::string(70'000, 'x')}}.dump()), 413, "body"});
  cases.push_back({"missions limit 0", s.get("/api/missions?limit=0"), 400, "limit"});
  cases.push_back({"missions limit 501", s.get("/api/missions?limit=501"), 400, "limit"});
  cases.push_back({"maps offset -1", s.get("/api/maps?offset=-1"), 400, "offset"});
  cases.push_back({"pdms limit 1e300", s.get(pdms + "?limit=1e300"), 400, "limit"});
  cases.push_back({"map 404", s.get("/api/maps/nope"), 404, "id"});
  cases.push_back({"mission 404", s.get("/api/missions/nope"), 404, "id"});
  for (auto& c : cases) {
    CAPTURE(c.what);
    CAPTURE(c.r.body);
    CHECK(c.r.status == c.status);
    CHECK(errorField(c.r) == c.field);
    // No server path in any message.
    CHECK(c.r.body.find(tmp.path.string()) == std::string::npos);
  }
  // A DEM upload with an absurd cell size: refused, nothing left behind in tmp.
  Raster<float> z(GridGeometry{20, 20, 1.0, 1.0}, 1.0f);
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100020, 0, -1};
  maps::writeGeoTiff(tmp.str("dem.tif"), z);
  std::ifstream in(tmp.str("dem.tif"), std::ios::binary);
  const std::string dem((std::istreambuf_iterator<char>(in)), {});
  for (const char* cell : {"1e-300", "1e300", "-1", "nan"}) {
    CAPTURE(cell);
    auto r = s.post(std::string("/api/maps?filename=d.tif&cell=") + cell, dem, "image/tiff");
    CHECK(r.status == 400);
    CHECK(errorField(r) == "cell");
  }
  CHECK(s.post("/api/maps?filename=d.tif&cell=0.5", dem, "image/tiff").status == 201);
  auto longName = s.post("/api/maps?filename=d.tif&name=" + std::string(201, 'n'), dem, "image/tiff");
  CHECK(longName.status == 400);
  CHECK(errorField(longName) == "name");
  // 256 long, thin, rotated components (the old 16-component worst case took ~20 s): accepted.
  Json extreme = {{"name", "thin"}, {"components", Json::array()}};
  for (int i = 0; i < 256; ++i)
    extreme["components"].push_back({{"x", 75}, {"y", 75}, {"sigma_x", 2e4}, {"sigma_y", 1e-3}, {"rotation_deg", i * 1.4}});
  CHECK(s.post(pdms, extreme.dump()).status == 201);
  CHECK(s.get("/api/health").status == 200);
}

TEST_CASE("hostile: listings are paginated in SQL and bounded in size") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  // 120 stored missions, each with a 200-character name and a ~4 KB spec (inserted directly:
  // what matters is the listing, not running them).
  for (int i = 0; i < 120; ++i) {
    store::MissionRecord m;
    m.id = "m" + std::to_string(1000 + i);
    m.mapId = map;
    m.planner = "coverage";
    m.spec = {{"name", std::string(200, 'n')}, {"params", {{"cost_table", std::vector<double>(400, 1.5)}}}};
    m.status = RunStatus::Succeeded;
    m.createdAt = "2026-01-01T00:00:" + std::to_string(10 + i / 10) + "." + std::to_string(100 + i) + "Z";
    s.db.insertMission(m);
  }
  auto first = s.get("/api/missions");
  REQUIRE(first.status == 200);
  CHECK(first.json().size() == 50);
  CHECK(first.headers["X-Total-Count"] == "120");
  CHECK(first.headers["Link"] == "</api/missions?limit=50&offset=50>; rel=\"next\"");
  CHECK(first.body.size() < 50 * 6000);
  CHECK(first.json()[0]["id"] == "m1119");  // newest first
  auto last = s.get("/api/missions?limit=50&offset=100");
  CHECK(last.json().size() == 20);
  CHECK(last.headers.count("Link") == 0);
  CHECK(last.json()[19]["id"] == "m1000");
  CHECK(s.get("/api/missions?limit=500").json().size() == 120);
  CHECK(s.get("/api/missions?offset=1000").json().empty());
  // Following the links visits every mission once.
  std::set<std::string> seen;
  std::string next = "/api/missions?limit=7";
  for (int pages = 0; !next.empty() && pages < 40; ++pages) {
    auto r = s.get(next);
    for (const auto& m : r.json()) seen.insert(m["id"].get<std::string>());
    next.clear();
    if (auto l = r.headers.find("Link"); l != r.headers.end()) next = l->second.substr(1, l->second.find('>') - 1);
  }
  CHECK(seen.size() == 120);

  // Maps and PDMs page the same way.
  const std::string pdms = "/api/maps/" + map + "/pdms";
  for (int i = 0; i < 3; ++i) REQUIRE(s.post(pdms, Json{{"random", 2}, {"seed", i + 1}}.dump()).status == 201);
  auto page = s.get(pdms + "?limit=2");
  CHECK(page.json().size() == 2);
  CHECK(page.headers["X-Total-Count"] == "3");
  CHECK(page.headers["Link"] == "<" + pdms + "?limit=2&offset=2>; rel=\"next\"");
  CHECK(s.get(pdms + "?limit=2&offset=2").json().size() == 1);
  auto maps = s.get("/api/maps?limit=1");
  CHECK(maps.json().size() == 1);
  CHECK(maps.headers["X-Total-Count"] == "1");
  auto detail = s.get("/api/maps/" + map).json();
  CHECK(detail["pdms"].size() == 3);
  CHECK(detail["pdms_total"] == 3);

  // The database pages in SQL.
  CHECK(s.db.listMissions(3, 118).size() == 2);
  CHECK(s.db.countMissions() == 120);
  CHECK(s.db.listPdms(map, 1, 1).size() == 1);
  CHECK(s.db.listPdms(map).size() == 3);
}

TEST_CASE("hostile: the map-body cache never keeps a map a write has changed or deleted") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  // The mechanism: a body read before an invalidation is not cached after it.
  const std::uint64_t ticket = s.ctx.mapCacheTicket();
  s.ctx.invalidateMap(map);
  CHECK_FALSE(s.ctx.cacheMapBody(map, "stale", 1, ticket));
  CHECK(s.ctx.cacheMapBody(map, "fresh", 1, s.ctx.mapCacheTicket()));
  s.ctx.invalidateMap(map);

  // A PDM created while GETs run is in every later GET.
  CHECK(s.get("/api/maps/" + map).json()["pdms"].empty());
  auto created = s.post("/api/maps/" + map + "/pdms", Json{{"random", 1}}.dump());
  REQUIRE(created.status == 201);
  CHECK(s.get("/api/maps/" + map).json()["pdms"].size() == 1);

  // GETs racing the delete (bounded: 3 threads, at most 200 requests each): afterwards 404.
  std::atomic<bool> stop{false};
  std::vector<std::thread> readers;
  std::atomic<int> reads{0};
  for (int t = 0; t < 3; ++t)
    readers.emplace_back([&] {
      for (int i = 0; i < 200 && !stop; ++i) {
        s.get("/api/maps/" + map);
        ++reads;
      }
    });
  test::waitUntil([&] { return reads >= 20; }, "20 GETs before the delete");
  CHECK(request(s.port(), "DELETE", "/api/maps/" + map).status == 200);
  // Twenty more GETs race past the delete (or the readers are done).
  const int atDelete = reads;
  test::waitUntil([&] { return reads >= std::min(atDelete + 20, 600); }, "20 GETs after the delete");
  stop = true;
  for (auto& r : readers) r.join();
  CHECK(s.get("/api/maps/" + map).status == 404);
}
