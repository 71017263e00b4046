// Keep-out zones over loopback (issue 13): GET|PUT /api/maps/{id}/zones, bad zones refused with
// their field, and missions with keep_out whose trajectories never enter a zone, on the default
// map and on a real DEM from ../shared/dems.
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "api_server.hpp"
#include "core/grid/geometry.hpp"
#include "maps/dem_io.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

test::ApiServerOptions options() {
  test::ApiServerOptions o;
  o.workers = 2;
  o.queue = 16;
  o.http.maxUploadBytes = 64ull << 20;
  return o;
}

json polygon(const std::vector<std::array<double, 2>>& ring) {
  json r = json::array();
  for (const auto& p : ring) r.push_back({p[0], p[1]});
  r.push_back({ring[0][0], ring[0][1]});
  return {{"type", "Feature"}, {"properties", json::object()}, {"geometry", {{"type", "Polygon"}, {"coordinates", {r}}}}};
}

json collection(std::vector<json> features) {
  return {{"type", "FeatureCollection"}, {"features", features}};
}

// A replacement of the whole set as the current version (the tests here are about the zones
// themselves; versions and conflicts are test_collab_api.cpp's).
test::HttpResult put(ApiServer& s, const std::string& target, const json& body) {
  const std::string base = target.substr(0, target.find('?'));
  const auto now = s.get(base);
  std::map<std::string, std::string> headers;
  if (now.status == 200) headers["If-Match"] = now.headers.at("ETag");
  return request(s.port(), "PUT", target, body.dump(), "application/json", headers);
}

// A zone set as sent: without the ids and versions the server adds.
json plain(json zones) {
  zones.erase("version");
  for (json& f : zones["features"]) {
    f.erase("id");
    f["properties"].erase("version");
  }
  return zones;
}

Polygon ringOf(const json& feature) {
  Ring ring;
  const json& c = feature["geometry"]["coordinates"][0];
  for (std::size_t i = 0; i + 1 < c.size(); ++i) ring.emplace_back(c[i][0].get<double>(), c[i][1].get<double>());
  return {ring};
}

// Every trajectory point of a result outside every zone; returns how many were checked.
int pointsOutside(const json& result, const json& zones) {
  std::vector<Polygon> polys;
  for (const auto& f : zones["features"]) polys.push_back(ringOf(f));
  int n = 0;
  for (const auto& r : result["rovers"])
    for (const auto& p : r["path"]) {
      const Eigen::Vector2d xy(p[0].get<double>(), p[1].get<double>());
      for (const auto& poly : polys) CHECK_FALSE(insidePolygon(poly, xy));
      ++n;
    }
  return n;
}

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace

TEST_CASE("zones api: a map's zones are stored, read back, and bad ones refused naming the field") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  const std::string path = "/api/maps/" + map + "/zones";
  auto empty = s.get(path);
  REQUIRE(empty.status == 200);
  CHECK(empty.json()["features"].empty());
  json zones = collection({polygon({{60, 40}, {90, 40}, {90, 110}, {60, 110}})});
  zones["features"][0]["properties"]["name"] = "crater rim";
  auto r = put(s, path, zones);
  REQUIRE(r.status == 200);
  CHECK(plain(r.json()) == zones);
  CHECK(plain(s.get(path).json()) == zones);

  auto bad = [&](json body, const std::string& field) {
    auto res = put(s, path, body);
    checkError(res, 400, field);
    CHECK(plain(s.get(path).json()) == zones);  // unchanged
  };
  json open = zones;
  open["features"][0]["geometry"]["coordinates"][0].erase(4);  // last position dropped
  bad(open, "zones.features[0].geometry.coordinates");
  bad(collection({zones["features"][0], polygon({{1, 1}, {2, 2}, {1, 1}})}), "zones.features[1].geometry.coordinates");
  json line = polygon({{1, 1}, {2, 2}, {3, 3}});  // no area
  bad(collection({line}), "zones.features[0].geometry.coordinates");
  json text = zones;
  text["features"][0]["geometry"]["coordinates"][0][2][0] = "NaN";
  bad(text, "zones.features[0].geometry.coordinates");
  bad(collection({polygon({{60, 40}, {900, 40}, {90, 110}})}), "zones.features[0].geometry.coordinates");  // off the map
  json point = zones;
  point["features"][0]["geometry"] = {{"type", "Point"}, {"coordinates", {1, 2}}};
  bad(point, "zones.features[0].geometry.type");
  bad(json{{"type", "Feature"}}, "zones.type");
  std::vector<json> many(65, polygon({{1, 1}, {5, 1}, {5, 5}}));
  bad(collection(many), "zones.features");
  std::vector<std::array<double, 2>> big;
  for (int i = 0; i < 1100; ++i) big.push_back({75 + 30 * std::cos(i * 0.0057), 75 + 30 * std::sin(i * 0.0057)});
  bad(collection({polygon(big)}), "zones.features[0].geometry.coordinates");  // over 1024 vertices
  json crs = zones;
  crs["crs"] = {{"type", "name"}, {"properties", {{"name", "EPSG:4326"}}}};
  bad(crs, "zones.crs");
  checkError(put(s, path + "?crs=wgs84", zones), 400, "crs");
  checkError(put(s, "/api/maps/nope/zones", zones), 404, "id");
  checkError(s.get("/api/maps/nope/zones"), 404, "id");
  // An empty collection clears them.
  CHECK(put(s, path, collection({})).status == 200);
  CHECK(s.get(path).json()["features"].empty());
  // A mission's keep_out is checked the same way, naming its own field.
  json m{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 10.5}, {"y", 10.5}}}}, {"keep_out", open}};
  checkError(s.postJson("/api/missions", m), 400, "keep_out.features[0].geometry.coordinates");
  m["keep_out"] = collection({polygon({{5, 5}, {20, 5}, {20, 20}, {5, 20}})});
  checkError(s.postJson("/api/missions", m), 400, "rovers[0]");  // the start is inside
}

TEST_CASE("zones api: ?crs=map imports a zone in the map's CRS into the local frame") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  Raster<float> z(GridGeometry{40, 50, 1.0, 1.0}, 0.0f);
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100040, 0, -1};
  z.geo.crsWkt = "EPSG:32633";
  maps::writeGeoTiff(tmp.str("small.tif"), z);
  auto up = s.post("/api/maps?name=small&filename=small.tif", readBytes(tmp.str("small.tif")), "application/octet-stream");
  REQUIRE(up.status == 201);
  const std::string map = up.json()["id"];
  // The lower-left corner is (500000, 4100000) in the CRS.
  const json inCrs = collection({polygon({{500010, 4100010}, {500020, 4100010}, {500020, 4100030}})});
  checkError(put(s, "/api/maps/" + map + "/zones", [&] { json j = inCrs; j["crs"] = "x"; return j; }()), 400, "zones.crs");
  auto r = put(s, "/api/maps/" + map + "/zones?crs=map", inCrs);
  REQUIRE(r.status == 200);
  const json stored = r.json();
  const json& c = stored["features"][0]["geometry"]["coordinates"][0];
  CHECK(c[0][0].get<double>() == doctest::Approx(10));
  CHECK(c[0][1].get<double>() == doctest::Approx(10));
  CHECK(c[2][0].get<double>() == doctest::Approx(20));
  CHECK(c[2][1].get<double>() == doctest::Approx(30));
}

TEST_CASE("zones api: coverage and team missions with keep_out never enter the zone (default map)") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  const json zones = collection({polygon({{55, 40}, {95, 45}, {90, 115}, {60, 110}})});
  json cov{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 30}, {"y", 75}, {"heading", 0}}}},
           {"params", {{"coverage", 0.9}}}, {"keep_out", zones}};
  json team{{"map", map}, {"planner", "team-search"},
            {"rovers", {{{"x", 40}, {"y", 70}, {"heading", 0}}, {{"x", 40}, {"y", 78}, {"heading", 0}}}},
            {"params", {{"targets", 4}}}, {"keep_out", zones}};
  std::vector<std::string> ids;
  for (const json& body : {cov, team}) {
    auto r = s.postJson("/api/missions", body);
    REQUIRE(r.status == 202);
    ids.push_back(r.json()["id"]);
  }
  for (std::size_t k = 0; k < ids.size(); ++k) {
    json m = s.waitFinished(ids[k], 180);
    MESSAGE(m["planner"].get<std::string>() << ": " << m["status"].get<std::string>() << " " << m["message"].get<std::string>());
    REQUIRE((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
    const json result = s.get("/api/missions/" + ids[k] + "/result.json").json();
    CHECK(pointsOutside(result, zones) > 20);
    if (k == 0) {
      CHECK(result["metrics"]["keep_out_cells"].get<double>() > 1000);
    } else {
      CHECK(result["metrics"]["keep_out_search_cells"].get<double>() >= 1);
      CHECK(result["metrics"]["collisions"] == 0);
    }
    // The mission file carries the zones: the re-run keeps out too, with the same result.
    const json file = s.get("/api/missions/" + ids[k] + "/mission.json").json();
    CHECK(file["keep_out"] == zones);
    if (k == 0) {
      auto again = s.postJson("/api/missions", file);
      REQUIRE(again.status == 202);
      const std::string id2 = again.json()["id"];
      REQUIRE(s.waitFinished(id2, 180)["status"] == "succeeded");
      CHECK(s.get("/api/missions/" + id2 + "/result.json").json()["rovers"] == result["rovers"]);
    }
  }
}

TEST_CASE("zones api: missions with keep_out on the HiRISE Gale DEM never enter the zone") {
  // ../shared/dems beside the checkout (a worktree elsewhere may name it in ROVERPLAN_SHARED_DEMS).
  const char* env = std::getenv("ROVERPLAN_SHARED_DEMS");
  const fs::path dems = env ? fs::path(env) : fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems";
  const fs::path dem = dems / "mars_gale_hirise_1m" / "missionDEM.tif";
  if (!fs::exists(dem)) {
    MESSAGE("SKIPPED: ../shared/dems absent");
    return;
  }
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  auto up = s.post("/api/maps?name=gale&filename=missionDEM.tif", readBytes(dem.string()), "application/octet-stream");
  REQUIRE(up.status == 201);
  const std::string map = up.json()["id"];
  const double w = up.json()["width_m"], h = up.json()["height_m"];
  // A band across the middle of the map, north-south, a fifth of its width.
  const json zones = collection({polygon({{0.45 * w, 0.1 * h}, {0.6 * w, 0.1 * h}, {0.6 * w, 0.9 * h}, {0.45 * w, 0.9 * h}})});
  // Starts west of it, on the first ground the planner accepts.
  auto launch = [&](json body, int rovers) -> std::string {
    for (double y = 0.3; y < 0.8; y += 0.05) {
      body["rovers"] = json::array();
      for (int k = 0; k < rovers; ++k) body["rovers"].push_back({{"x", 0.25 * w + 3 * k}, {"y", y * h}, {"heading", 0}});
      auto r = s.postJson("/api/missions", body);
      if (r.status == 202) return r.json()["id"];
      REQUIRE(r.status == 400);
    }
    FAIL("no start accepted");
    return "";
  };
  const std::string cov = launch({{"map", map}, {"planner", "coverage"}, {"params", {{"coverage", 0.9}}}, {"keep_out", zones}}, 1);
  const std::string team = launch({{"map", map}, {"planner", "team-search"}, {"params", {{"targets", 3}}}, {"keep_out", zones}}, 2);
  for (const std::string& id : {cov, team}) {
    json m = s.waitFinished(id, 240);
    MESSAGE(m["planner"].get<std::string>() << ": " << m["status"].get<std::string>() << " " << m["message"].get<std::string>());
    REQUIRE((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
    CHECK(pointsOutside(s.get("/api/missions/" + id + "/result.json").json(), zones) > 5);
  }
}
