// Several operators on one server (issue 26), over loopback: versions on every mutable object
// (stale If-Match -> 412 with the current object, none -> 428, creating never overwrites), zones
// one at a time, history bounded and restored, operator names, and the versions a mission used.
// The event stream is test_events_api.cpp's.
#include <doctest/doctest.h>

#include <sstream>

#include "api_server.hpp"
#include "server/cli/token_file.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

// a + b, appended (GCC 12 warns on `"x" + std::to_string(n)`, -Wrestrict).
std::string cat(std::string a, const std::string& b) {
  a += b;
  return a;
}

json polygon(const std::vector<std::array<double, 2>>& ring, const std::string& name = "") {
  json r = json::array();
  for (const auto& p : ring) r.push_back({p[0], p[1]});
  r.push_back({ring[0][0], ring[0][1]});
  json f{{"type", "Feature"}, {"properties", json::object()}, {"geometry", {{"type", "Polygon"}, {"coordinates", {r}}}}};
  if (!name.empty()) f["properties"]["name"] = name;
  return f;
}

json collection(std::vector<json> features) { return {{"type", "FeatureCollection"}, {"features", features}}; }

test::HttpResult send(ApiServer& s, const std::string& method, const std::string& target, const json& body,
                      const std::map<std::string, std::string>& headers = {}) {
  return request(s.port(), method, target, body.is_null() ? "" : body.dump(), body.is_null() ? "" : "application/json",
                 headers);
}

std::map<std::string, std::string> ifMatch(long long v) { return {{"If-Match", cat("\"v", std::to_string(v)) + "\""}}; }

test::ApiServerOptions options() {
  test::ApiServerOptions o;
  o.workers = 1;
  return o;
}

}  // namespace

TEST_CASE("versions: a map's zone set is versioned; stale writes get 412 with the current set, none 428") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string path = "/api/maps/" + s.defaultMap() + "/zones";
  auto none = s.get(path);
  REQUIRE(none.status == 200);
  CHECK(none.json()["version"] == 0);
  CHECK(none.headers["ETag"] == "\"v0\"");

  // A first save needs no version (creating overwrites nothing); operator A's zone.
  const json a = collection({polygon({{60, 40}, {90, 40}, {90, 110}}, "A")});
  auto first = send(s, "PUT", path, a);
  REQUIRE(first.status == 200);
  CHECK(first.json()["version"] == 1);
  CHECK(first.headers["ETag"] == "\"v1\"");
  const std::string zoneA = first.json()["features"][0]["id"];
  CHECK(first.json()["features"][0]["properties"]["version"] == 1);

  // Operator B read version 0 too: its save is refused whole, A's zone stays, B is told the current set.
  const json b = collection({polygon({{10, 10}, {30, 10}, {30, 30}}, "B")});
  checkError(send(s, "PUT", path, b), 428, "precondition_required", "If-Match");
  auto stale = send(s, "PUT", path, b, ifMatch(0));
  checkError(stale, 412, "version_conflict", "If-Match");
  CHECK(stale.json()["error"]["current"]["version"] == 1);
  CHECK(stale.json()["error"]["current"]["features"][0]["properties"]["name"] == "A");
  CHECK(stale.headers["ETag"] == "\"v1\"");
  CHECK(s.get(path).json()["features"].size() == 1);

  // B merges with what it was shown and names version 1 (in the body this time): both kept.
  json merged = stale.json()["error"]["current"];
  merged["features"].push_back(b["features"][0]);
  auto both = send(s, "PUT", path, merged);
  REQUIRE(both.status == 200);
  CHECK(both.json()["version"] == 2);
  REQUIRE(both.json()["features"].size() == 2);
  CHECK(both.json()["features"][0]["id"] == zoneA);                    // A's zone kept its id...
  CHECK(both.json()["features"][0]["properties"]["version"] == 1);    // ...and version (unchanged)
  CHECK(both.json()["features"][1]["id"] != zoneA);

  // Hostile preconditions, each named.
  checkError(send(s, "PUT", path, merged, {{"If-Match", "v2x"}}), 400, "invalid_header", "If-Match");
  checkError(send(s, "PUT", path, merged, {{"If-Match", "*"}}), 400, "invalid_header", "If-Match");
  checkError(send(s, "PUT", path, merged, {{"If-Match", "\"v99999999999999999999\""}}), 400, "invalid_header", "If-Match");
  checkError(send(s, "PUT", path, merged, {{"If-Match", "\"v1\", \"v2\""}}), 400, "invalid_header", "If-Match");
  // Strong comparison (RFC 9110 §13.1.1): a weak tag and a padded number name no version.
  checkError(send(s, "PUT", path, merged, {{"If-Match", "W/\"v2\""}}), 400, "invalid_header", "If-Match");
  checkError(send(s, "PUT", path, merged, {{"If-Match", "\"v02\""}}), 400, "invalid_header", "If-Match");
  json wrongType = merged;
  wrongType["version"] = "2";
  checkError(send(s, "PUT", path, wrongType), 400, "invalid_field", "version");
  json disagree = merged;
  disagree["version"] = 1;
  checkError(send(s, "PUT", path, disagree, ifMatch(2)), 400, "invalid_field", "version");
  checkError(request(s.port(), "PUT", path, merged.dump(), "application/json", {{"X-Operator", std::string(41, 'x')}}), 400,
             "invalid_header", "X-Operator");
  CHECK(s.get(path).json()["version"] == 2);
}

TEST_CASE("versions: zones one at a time: add, change, delete, each checked against its own version") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string path = "/api/maps/" + s.defaultMap() + "/zones";
  auto added = send(s, "POST", path, polygon({{60, 40}, {90, 40}, {90, 110}}, "rim"));
  REQUIRE(added.status == 201);
  const std::string z1 = added.json()["id"];
  CHECK(added.json()["version"] == 1);
  CHECK(added.json()["zones_version"] == 1);
  CHECK(added.headers["Location"] == path + "/" + z1);
  // Another operator adds a zone meanwhile: no version needed, nothing lost.
  auto other = send(s, "POST", path, polygon({{10, 10}, {30, 10}, {30, 30}}));
  REQUIRE(other.status == 201);
  const std::string z2 = other.json()["id"];
  CHECK(z2 != z1);
  CHECK(s.get(path).json()["features"].size() == 2);
  // A set that names one zone id twice is refused: the second zone could never be reached.
  {
    json twice = s.get(path).json();
    json dup = twice["features"][0];
    twice["features"].push_back(dup);
    twice.erase("version");
    const auto r = send(s, "PUT", path, twice, ifMatch(2));
    CHECK(r.status == 400);
    CHECK(r.json()["error"]["field"] == "zones.features[2].id");
    CHECK(s.get(path).json()["features"].size() == 2);
  }

  // Changing z1 names z1's version (1), not the set's (2): the other zone's add does not conflict.
  json moved = polygon({{61, 41}, {91, 41}, {91, 111}}, "rim");
  checkError(send(s, "PUT", path + "/" + z1, moved), 428, "precondition_required", "If-Match");
  auto changed = send(s, "PUT", path + "/" + z1, moved, ifMatch(1));
  REQUIRE(changed.status == 200);
  CHECK(changed.json()["version"] == 2);
  CHECK(changed.headers["ETag"] == "\"v2\"");
  CHECK(s.get(path + "/" + z1).json()["geometry"]["coordinates"][0][0][0] == 61);
  // A second editor still at version 1: 412 with the zone as it is now.
  auto stale = send(s, "PUT", path + "/" + z1, polygon({{62, 40}, {90, 40}, {90, 110}}), ifMatch(1));
  checkError(stale, 412, "version_conflict", "If-Match");
  CHECK(stale.json()["error"]["current"]["version"] == 2);
  CHECK(stale.json()["error"]["current"]["id"] == z1);
  // Bad zones name the zone's field; unknown zones 404 naming it.
  checkError(send(s, "PUT", path + "/" + z1, polygon({{1, 1}, {2, 2}, {3, 3}}), ifMatch(2)), 400,
             "zone.geometry.coordinates");
  checkError(send(s, "POST", path, json{{"type", "Point"}}), 400, "zone");
  checkError(send(s, "PUT", path + "/z999", moved, ifMatch(1)), 404, "zone");
  checkError(request(s.port(), "DELETE", path + "/z999", "", "", ifMatch(1)), 404, "zone");
  checkError(s.get(path + "/nope"), 404, "zone");
  checkError(send(s, "POST", "/api/maps/nope/zones", moved), 404, "id");

  // Delete: its version, else 428 / 412.
  checkError(request(s.port(), "DELETE", path + "/" + z2), 428, "precondition_required", "If-Match");
  checkError(request(s.port(), "DELETE", path + "/" + z2, "", "", ifMatch(7)), 412, "version_conflict", "If-Match");
  auto gone = request(s.port(), "DELETE", path + "/" + z2, "", "", ifMatch(1));
  REQUIRE(gone.status == 200);
  CHECK(gone.json()["deleted"] == z2);
  const json now = s.get(path).json();
  REQUIRE(now["features"].size() == 1);
  CHECK(now["features"][0]["id"] == z1);
  CHECK(now["version"] == gone.json()["zones_version"]);
  // Ids are never handed out twice on a map.
  auto third = send(s, "POST", path, polygon({{10, 10}, {30, 10}, {30, 30}}));
  REQUIRE(third.status == 201);
  CHECK(third.json()["id"] != z2);
}

TEST_CASE("versions: PDMs change by version, keep their history (bounded) and restore an old one") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  const json comps = json::array({{{"x", 50}, {"y", 50}, {"sigma_x", 10}}});
  auto made = request(s.port(), "POST", "/api/maps/" + map + "/pdms", json{{"name", "lake"}, {"components", comps}}.dump(),
                      "application/json", {{"X-Operator", "Ada"}});
  REQUIRE(made.status == 201);
  CHECK(made.json()["version"] == 1);
  const std::string pdm = "/api/maps/" + map + "/pdms/" + made.json()["id"].get<std::string>();
  CHECK(s.get(pdm).headers["ETag"] == "\"v1\"");

  checkError(send(s, "PUT", pdm, json{{"name", "sea"}}), 428, "precondition_required", "If-Match");
  auto renamed = send(s, "PUT", pdm, json{{"name", "sea"}, {"version", 1}});
  REQUIRE(renamed.status == 200);
  CHECK(renamed.json()["version"] == 2);
  CHECK(renamed.json()["layer"].get<std::string>().find("v=2") != std::string::npos);
  auto stale = send(s, "PUT", pdm, json{{"name", "ocean"}}, ifMatch(1));
  checkError(stale, 412, "version_conflict", "If-Match");
  CHECK(stale.json()["error"]["current"]["name"] == "sea");
  // New components: a new mass (the overview layer of the new version is another file).
  const json moved = json::array({{{"x", 80}, {"y", 80}, {"sigma_x", 5}}});
  auto edited = send(s, "PUT", pdm, json{{"components", moved}}, ifMatch(2));
  REQUIRE(edited.status == 200);
  CHECK(edited.json()["components"][0]["x"] == 80);
  CHECK(s.get("/api/maps/" + map + "/layers/pdm.png?max=64&pdm=" + made.json()["id"].get<std::string>()).status == 200);
  CHECK(s.get("/api/maps/" + map + "/tiles/pdm/0/0/0.png?pdm=" + made.json()["id"].get<std::string>()).headers["ETag"].find("-v3") !=
        std::string::npos);
  checkError(send(s, "PUT", pdm, json{{"components", json::array()}}, ifMatch(3)), 400, "components");
  checkError(send(s, "PUT", pdm, json{{"seed", 3}}, ifMatch(3)), 400, "seed");
  checkError(request(s.port(), "DELETE", pdm, "", "", ifMatch(1)), 412, "version_conflict", "If-Match");

  // History: every version with who and when; one version whole; restore makes it the newest.
  auto hist = s.get(pdm + "/history").json();
  REQUIRE(hist.size() == 3);
  CHECK(hist[0]["version"] == 3);
  CHECK(hist[2]["by"] == "Ada");
  auto v1 = s.get(pdm + "/history/1").json();
  CHECK(v1["body"]["name"] == "lake");
  checkError(s.get(pdm + "/history/9"), 404, "version");
  checkError(s.get(pdm + "/history/x"), 404, "version");
  checkError(send(s, "POST", pdm + "/restore", json{{"restore", 1}}), 428, "precondition_required", "If-Match");
  checkError(send(s, "POST", pdm + "/restore", json{{"restore", 1}}, ifMatch(2)), 412, "version_conflict", "If-Match");
  checkError(send(s, "POST", pdm + "/restore", json{{"restore", "1"}}, ifMatch(3)), 400, "restore");
  auto restored = send(s, "POST", pdm + "/restore", json{{"restore", 1}}, ifMatch(3));
  REQUIRE(restored.status == 200);
  CHECK(restored.json()["version"] == 4);
  CHECK(restored.json()["name"] == "lake");
  CHECK(restored.json()["components"][0]["x"] == 50);

  // At most 50 versions are kept: the oldest go.
  for (long long v = 4; v < 60; ++v) REQUIRE(send(s, "PUT", pdm, json{{"name", cat("n", std::to_string(v))}}, ifMatch(v)).status == 200);
  hist = s.get(pdm + "/history").json();
  CHECK(hist.size() == 50);
  CHECK(hist[0]["version"] == 60);
  CHECK(hist[49]["version"] == 11);
  checkError(s.get(pdm + "/history/1"), 404, "version");
}

TEST_CASE("versions: zone sets keep their history and restore one, deleted zones coming back with their ids") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string path = "/api/maps/" + s.defaultMap() + "/zones";
  auto one = send(s, "PUT", path, collection({polygon({{60, 40}, {90, 40}, {90, 110}})}));
  REQUIRE(one.status == 200);
  const std::string z1 = one.json()["features"][0]["id"];
  REQUIRE(request(s.port(), "DELETE", path + "/" + z1, "", "", ifMatch(1)).status == 200);
  auto hist = s.get(path + "/history").json();
  REQUIRE(hist.size() == 2);
  CHECK(s.get(path + "/history/1").json()["body"]["features"][0]["id"] == z1);
  auto back = send(s, "POST", path + "/restore", json{{"restore", 1}}, ifMatch(2));
  REQUIRE(back.status == 200);
  CHECK(back.json()["version"] == 3);
  CHECK(back.json()["features"][0]["id"] == z1);
  CHECK(back.json()["features"][0]["properties"]["version"] == 2);
  checkError(send(s, "POST", path + "/restore", json{{"restore", 1}}, ifMatch(2)), 412, "version_conflict", "If-Match");
}

TEST_CASE("versions: mission labels are versioned; a mission records the PDM and zone versions it used") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  auto zones = send(s, "PUT", "/api/maps/" + map + "/zones", collection({polygon({{60, 40}, {90, 40}, {90, 110}})}));
  REQUIRE(zones.status == 200);
  auto p = s.postJson("/api/maps/" + map + "/pdms", {{"name", "p"}, {"components", json::array({{{"x", 50}, {"y", 50}, {"sigma_x", 10}}})}});
  REQUIRE(p.status == 201);
  json m{{"map", map}, {"pdm", p.json()["id"]}, {"planner", "coverage"}, {"rovers", {{{"x", 10.5}, {"y", 10.5}, {"heading", 0}}}},
         {"params", {{"coverage", 0.2}}}, {"keep_out", zones.json()}};
  auto launched = s.postJson("/api/missions", m);
  REQUIRE(launched.status == 202);
  const std::string id = launched.json()["id"];
  CHECK(launched.json()["spec"]["used"]["pdm_version"] == 1);
  CHECK(launched.json()["spec"]["used"]["zones_version"] == 1);
  s.waitFinished(id);
  const std::string target = "/api/missions/" + id;
  const long long v = s.get(target).json()["version"];
  CHECK(s.get(target).headers["ETag"] == cat("\"v", std::to_string(v)) + "\"");
  checkError(send(s, "PATCH", target, json{{"label", "first"}}), 428, "precondition_required", "If-Match");
  auto ok = send(s, "PATCH", target, json{{"label", "first"}}, ifMatch(v));
  REQUIRE(ok.status == 200);
  CHECK(ok.json()["version"] == v + 1);
  auto stale = send(s, "PATCH", target, json{{"label", "second"}, {"version", v}});
  checkError(stale, 412, "version_conflict", "If-Match");
  CHECK(stale.json()["error"]["current"]["label"] == "first");
  auto file = s.get(target + "/mission.json").json();
  CHECK(file["used"]["pdm_version"] == 1);
  // The file launches again ("used" is the server's to write).
  CHECK(s.postJson("/api/missions", file).status == 202);
}

TEST_CASE("versions: they survive a restart of the server on the same data dir") {
  TempDir tmp;
  std::string pdm;
  {
    ApiServer s(tmp.str("data"), options());
    const std::string path = "/api/maps/" + s.defaultMap() + "/zones";
    REQUIRE(send(s, "PUT", path, collection({polygon({{60, 40}, {90, 40}, {90, 110}})})).status == 200);
    REQUIRE(send(s, "PUT", path, collection({}), ifMatch(1)).status == 200);
    auto p = s.postJson("/api/maps/" + s.defaultMap() + "/pdms", {{"components", json::array({{{"x", 50}, {"y", 50}, {"sigma_x", 10}}})}});
    pdm = "/api/maps/" + s.defaultMap() + "/pdms/" + p.json()["id"].get<std::string>();
    REQUIRE(send(s, "PUT", pdm, json{{"name", "kept"}}, ifMatch(1)).status == 200);
  }
  ApiServer again(tmp.str("data"), options());
  CHECK(again.get("/api/maps/" + again.defaultMap() + "/zones").json()["version"] == 2);
  CHECK(again.get(pdm).json()["version"] == 2);
  checkError(send(again, "PUT", pdm, json{{"name", "x"}}, ifMatch(1)), 412, "version_conflict", "If-Match");
}

TEST_CASE("operators: token files name their operators; events and history say who") {
  std::istringstream file("# team\nada:tok-ada-1\n\nplain-token\nGrace Hopper:tok-grace\r\n");
  const auto tokens = cli::parseTokenFile(file);
  REQUIRE(tokens.size() == 3);
  CHECK(tokens[0] == std::pair<std::string, std::string>{"ada", "tok-ada-1"});
  CHECK(tokens[1] == std::pair<std::string, std::string>{"", "plain-token"});
  CHECK(tokens[2] == std::pair<std::string, std::string>{"Grace Hopper", "tok-grace"});
  for (const char* bad : {":tok\n", "ada:\n", "a:has space\n", "x:t\ny:t\n", "\n# none\n", "ada:b:c d\n"}) {
    std::istringstream in(bad);
    CHECK_THROWS_AS(cli::parseTokenFile(in), std::invalid_argument);
  }

  TempDir tmp;
  test::ApiServerOptions o = options();
  o.http.token = "tok-ada-1";
  o.http.namedTokens = tokens;
  ApiServer s(tmp.str("data"), o);
  const auto as = [](const std::string& token) { return std::map<std::string, std::string>{{"Authorization", "Bearer " + token}}; };
  const std::string map = request(s.port(), "GET", "/api/maps", "", "", as("plain-token")).json()[0]["id"];
  const std::string path = "/api/maps/" + map + "/zones";
  CHECK(request(s.port(), "GET", path, "", "", as("wrong")).status == 401);
  auto put = request(s.port(), "PUT", path, collection({polygon({{60, 40}, {90, 40}, {90, 110}})}).dump(), "application/json",
                     as("tok-grace"));
  REQUIRE(put.status == 200);
  // A named token's name wins over X-Operator; a plain token's request may say its name.
  auto h = as("tok-ada-1");
  h["X-Operator"] = "Mallory";
  h["If-Match"] = "\"v1\"";
  REQUIRE(request(s.port(), "PUT", path, collection({}).dump(), "application/json", h).status == 200);
  auto p = as("plain-token");
  p["X-Operator"] = "Katherine";
  p["If-Match"] = "\"v2\"";
  REQUIRE(request(s.port(), "PUT", path, collection({}).dump(), "application/json", p).status == 200);
  // A name that would show as something it is not (a right-to-left override, a zero-width space)
  // is refused as in every other name.
  for (const char* hidden : {"\xe2\x80\xae" "evil", "a\xe2\x80\x8b" "b"}) {
    auto bad = as("plain-token");
    bad["X-Operator"] = hidden;
    CHECK(request(s.port(), "GET", path, "", "", bad).status == 400);
  }
  const json hist = request(s.port(), "GET", path + "/history", "", "", as("plain-token")).json();
  REQUIRE(hist.size() == 3);
  CHECK(hist[0]["by"] == "Katherine");
  CHECK(hist[1]["by"] == "ada");
  CHECK(hist[2]["by"] == "Grace Hopper");
}

TEST_CASE("versions: a map's name is versioned: rename with the version read, stale 412, none 428") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  const std::string target = "/api/maps/" + map;
  auto read = s.get(target);
  REQUIRE(read.status == 200);
  CHECK(read.json()["version"] == 1);
  CHECK(read.headers["ETag"] == "\"v1\"");
  CHECK(s.get(target).headers["ETag"] == "\"v1\"");  // the cached body answers with its ETag too

  checkError(send(s, "PATCH", target, json{{"name", "Gale east"}}), 428, "precondition_required", "If-Match");
  auto ok = send(s, "PATCH", target, json{{"name", "Gale east"}}, ifMatch(1));
  REQUIRE(ok.status == 200);
  CHECK(ok.json()["name"] == "Gale east");
  CHECK(ok.json()["version"] == 2);
  CHECK(ok.headers["ETag"] == "\"v2\"");
  // GET answers the new name at once (its cached body was dropped), and so do the lists.
  auto again = s.get(target);
  CHECK(again.json()["name"] == "Gale east");
  CHECK(again.headers["ETag"] == "\"v2\"");
  CHECK(s.get("/api/maps").json()[0]["name"] == "Gale east");

  // A second operator who read version 1: refused, told the current map; nothing written.
  auto stale = send(s, "PATCH", target, json{{"name", "Jezero"}, {"version", 1}});
  checkError(stale, 412, "version_conflict", "If-Match");
  CHECK(stale.json()["error"]["current"]["name"] == "Gale east");
  CHECK(stale.json()["error"]["current"]["version"] == 2);
  CHECK(stale.headers["ETag"] == "\"v2\"");
  CHECK(s.get(target).json()["name"] == "Gale east");
  // The body's version may go with an If-Match naming the same one, never another.
  checkError(send(s, "PATCH", target, json{{"name", "x"}, {"version", 1}}, ifMatch(2)), 400, "invalid_field", "version");
  checkError(send(s, "PATCH", "/api/maps/nope", json{{"name", "x"}}, ifMatch(1)), 404, "not_found", "id");
}

TEST_CASE("versions: hostile map and rename bodies are refused naming the field") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string target = "/api/maps/" + s.defaultMap();
  const std::string tooLong(201, 'a'), nul = std::string("a\0b", 3);
  for (const json& bad : {json{{"name", ""}}, json{{"name", "   "}}, json{{"name", tooLong}}, json{{"name", nul}},
                          json{{"name", "a\x01"}}, json{{"name", "a\u202eb"}}, json{{"name", 7}}, json::object()})
    checkError(send(s, "PATCH", target, bad, ifMatch(1)), 400, "invalid_field", "name");
  checkError(send(s, "PATCH", target, json{{"name", "ok"}, {"meta", 1}}, ifMatch(1)), 400, "unknown_field", "meta");
  checkError(send(s, "PATCH", target, json::array({1}), ifMatch(1)), 400, "bad_json", "body");
  checkError(send(s, "PATCH", target, json{{"name", "ok"}}, {{"If-Match", "W/\"v1\""}}), 400, "invalid_header", "If-Match");
  checkError(send(s, "PATCH", target, json{{"name", "ok"}, {"version", -1}}), 400, "invalid_field", "version");
  checkError(request(s.port(), "PATCH", target, "name=ok", "text/plain", ifMatch(1)), 415, "content-type");
  // 200 characters is the limit, and it is taken.
  CHECK(send(s, "PATCH", target, json{{"name", std::string(200, 'b')}}, ifMatch(1)).status == 200);
  CHECK(s.get(target).json()["version"] == 2);
}

TEST_CASE("versions: a map cannot take another map's name; a map stored before versions is version 1") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string target = "/api/maps/" + s.defaultMap();
  store::MapRecord other{"other-map", "Jezero", "2026-01-01T00:00:00.000Z", json::object()};
  s.db.insertMap(other);
  CHECK(s.get("/api/maps/other-map").json()["version"] == 1);
  auto taken = send(s, "PATCH", target, json{{"name", "Jezero"}}, ifMatch(1));
  checkError(taken, 409, "name_taken", "name");
  CHECK(s.get(target).json()["version"] == 1);  // nothing written
  // Its own name again is no clash: a new version.
  const std::string own = s.get(target).json()["name"];
  CHECK(send(s, "PATCH", target, json{{"name", own}}, ifMatch(1)).status == 200);
}
