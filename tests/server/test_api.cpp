// The REST + WebSocket API over loopback, with an in-process server on an ephemeral port.
#include <map>
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "api_server.hpp"
#include "maps/dem_io.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// This file's servers: two mission workers, sixteen queued missions, uploads up to 64 MiB.
test::ApiServerOptions options() {
  test::ApiServerOptions o;
  o.workers = 2;
  o.queue = 16;
  o.http.maxUploadBytes = 64ull << 20;
  return o;
}

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A small georeferenced DEM file (40 × 50 cells of 1 m, gentle slope) as GeoTIFF bytes.
std::string smallDemBytes(const TempDir& tmp) {
  Raster<float> z(GridGeometry{40, 50, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 50; ++c) z(r, c) = 0.05f * c + 0.02f * r;
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100040, 0, -1};
  const std::string path = tmp.str("small.tif");
  maps::writeGeoTiff(path, z);
  return readBytes(path);
}

json coverageMission(const std::string& map, double x = 10.5, double y = 10.5) {
  return {{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", x}, {"y", y}, {"heading", 0}}}},
          {"params", {{"coverage", 0.5}}}};
}

}  // namespace

TEST_CASE("api: health, planners, and an OpenAPI document naming every route") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  auto h = s.get("/api/health");
  CHECK(h.status == 200);
  CHECK(h.json()["status"] == "ok");
  auto planners = s.get("/api/planners").json();
  REQUIRE(planners.size() >= 1);
  CHECK(planners[0]["name"] == "coverage");
  CHECK(planners[0]["params"].size() > 10);
  json doc = s.get("/api/openapi.json").json();
  CHECK(doc["openapi"] == "3.0.3");
  // HTTP routes are operations; WebSocket streams, which OpenAPI 3.0 cannot describe, x-websockets.
  for (const auto& r : s.router.routes())
    CHECK_MESSAGE(doc[r.method == "WS" ? "x-websockets" : "paths"].contains(r.pattern), r.pattern);
  checkError(s.get("/api/nope"), 404, "path");
}

TEST_CASE("api: the default map is there, with metadata and layers in three formats") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  auto list = s.get("/api/maps").json();
  REQUIRE(list.size() == 1);
  json m = list[0];
  CHECK(m["rows"] == 600);
  CHECK(m["cell_size_m"].get<double>() == doctest::Approx(0.25));
  CHECK(m["classes"]["traversable_pct"].get<double>() > 70);
  const std::string id = m["id"];
  auto png = s.get("/api/maps/" + id + "/layers/traversability.png?max=128");
  CHECK(png.status == 200);
  CHECK(png.headers["Content-Type"] == "image/png");
  CHECK(png.body.substr(1, 3) == "PNG");
  auto f32 = s.get("/api/maps/" + id + "/layers/elevation.f32");
  CHECK(f32.status == 200);
  CHECK(f32.body.size() == 600u * 600u * 4u);
  CHECK(f32.headers["X-Rows"] == "600");
  auto tif = s.get("/api/maps/" + id + "/layers/slope.tif");
  CHECK(tif.status == 200);
  CHECK(tif.body.substr(0, 2) == "II");
  checkError(s.get("/api/maps/" + id + "/layers/nope.png"), 404, "layer");
  checkError(s.get("/api/maps/" + id + "/layers/slope.jpg"), 404, "format");
  checkError(s.get("/api/maps/" + id + "/layers/pdm.png"), 404, "pdm");  // no PDM yet
  checkError(s.get("/api/maps/doesnotexist"), 404, "id");
}

TEST_CASE("api: DEM upload as a raw body, as multipart, bad files and deletion") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string bytes = smallDemBytes(tmp);
  auto r = request(s.port(), "POST", "/api/maps?name=small&filename=small.tif", bytes, "image/tiff");
  REQUIRE(r.status == 201);
  json m = r.json();
  CHECK(m["name"] == "small");
  CHECK(m["rows"] == 40);
  CHECK(m["cols"] == 50);

  // multipart/form-data with a name field and a file part, resampled to 2 m cells.
  const std::string boundary = "XyZBoundary42";
  std::string body = "--" + boundary + "\r\nContent-Disposition: form-data; name=\"name\"\r\n\r\nhalf\r\n--" +
                     boundary + "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"dem.tif\"\r\n"
                     "Content-Type: image/tiff\r\n\r\n" + bytes + "\r\n--" + boundary + "--\r\n";
  r = request(s.port(), "POST", "/api/maps?cell=2", body, "multipart/form-data; boundary=" + boundary);
  REQUIRE(r.status == 201);
  CHECK(r.json()["name"] == "half");
  CHECK(r.json()["cols"] == 25);

  checkError(request(s.port(), "POST", "/api/maps?filename=x.tif", "definitely not a raster", "image/tiff"), 400, "file");
  checkError(request(s.port(), "POST", "/api/maps", "", "image/tiff"), 400, "file");
  checkError(request(s.port(), "POST", "/api/maps?cell=-1&filename=a.tif", bytes, "image/tiff"), 400, "cell");
  CHECK(s.get("/api/maps").json().size() == 3);
  // Nothing of the failed uploads is left behind.
  CHECK(fs::is_empty(s.dir.tmpDir()));

  const std::string id = m["id"];
  CHECK(request(s.port(), "DELETE", "/api/maps/" + id).status == 200);
  CHECK(s.get("/api/maps/" + id).status == 404);
  CHECK(request(s.port(), "DELETE", "/api/maps/" + id).status == 404);
}

TEST_CASE("api: a PDS3 product uploaded as an .IMG + .LBL multipart pair") {
  const fs::path dir = fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems" / "moon_lola_ldem4_global";
  if (!fs::exists(dir)) {
    MESSAGE("SKIPPED: ../shared/dems absent");
    return;
  }
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string b = "PairBoundary";
  std::string body;
  for (const char* f : {"LDEM_4.LBL", "LDEM_4.IMG"})
    body += "--" + b + "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"" + f + "\"\r\n\r\n" +
            readBytes((dir / f).string()) + "\r\n";
  body += "--" + b + "--\r\n";
  auto r = request(s.port(), "POST", "/api/maps?name=lola", body, "multipart/form-data; boundary=" + b);
  REQUIRE(r.status == 201);
  CHECK(r.json()["driver"] == "PDS");
  CHECK(r.json()["rows"] == 720);
}

TEST_CASE("api: PDMs from Gaussians, random and raster, errors name the field") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  auto r = s.postJson("/api/maps/" + map + "/pdms",
                      {{"name", "two"}, {"components", {{{"x", 40}, {"y", 50}, {"sigma_x", 10}},
                                                        {{"x", 110}, {"y", 100}, {"sigma_x", 8}, {"sigma_y", 20}, {"rotation_deg", 30}, {"weight", 2}}}}});
  REQUIRE(r.status == 201);
  const std::string pdm = r.json()["id"];
  CHECK(r.json()["components"].size() == 2);
  CHECK(s.postJson("/api/maps/" + map + "/pdms", {{"random", 4}, {"seed", 7}}).status == 201);
  checkError(s.postJson("/api/maps/" + map + "/pdms", {{"components", {{{"x", 1}, {"y", 1}, {"sigma_x", -3}}}}}), 400,
             "components[0].sigma_x");
  checkError(s.postJson("/api/maps/" + map + "/pdms", {{"components", {{{"x", 1}, {"y", 1}, {"sigma_x", 3}, {"colour", 1}}}}}), 400,
             "components[0].colour");
  CHECK(s.get("/api/maps/" + map + "/pdms").json().size() == 2);
  auto png = s.get("/api/maps/" + map + "/layers/pdm.png?max=100&pdm=" + pdm);
  CHECK(png.status == 200);
  // A raster PDM: the map's own elevation as weights (shifted positive) would do; use the PDM tif.
  auto tif = s.get("/api/maps/" + map + "/layers/pdm.tif?pdm=" + pdm);
  REQUIRE(tif.status == 200);
  r = request(s.port(), "POST", "/api/maps/" + map + "/pdms?name=fromraster&filename=p.tif", tif.body, "image/tiff");
  CHECK(r.status == 201);
  CHECK(request(s.port(), "DELETE", "/api/maps/" + map + "/pdms/" + pdm).status == 200);
  CHECK(s.get("/api/maps/" + map + "/pdms/" + pdm).status == 404);
}

TEST_CASE("api: missions are validated fully before they are queued") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  json m = coverageMission(map);
  m["planner"] = "teleport";
  checkError(s.postJson("/api/missions", m), 400, "planner");
  m = coverageMission("nope");
  checkError(s.postJson("/api/missions", m), 400, "map");
  checkError(s.postJson("/api/missions", coverageMission(map, 500, 10)), 400, "rovers[0]");
  m = coverageMission(map);
  m["params"]["sense_radius"] = 7;
  checkError(s.postJson("/api/missions", m), 400, "params.sense_radius");
  m = coverageMission(map);
  m["params"]["warp_drive"] = true;
  checkError(s.postJson("/api/missions", m), 400, "params.warp_drive");
  m = coverageMission(map);
  m["rovers"] = json::array();
  checkError(s.postJson("/api/missions", m), 400, "rovers");
  m = coverageMission(map);
  m["extra"] = 1;
  checkError(s.postJson("/api/missions", m), 400, "extra");
  checkError(request(s.port(), "POST", "/api/missions", "{not json", "application/json"), 400, "body");
  CHECK(s.get("/api/missions").json().empty());
}

TEST_CASE("api: a coverage mission runs, reports metrics and exports its results") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  json body = coverageMission(map);
  body["params"] = json::object();  // every default
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  json m = s.waitFinished(id);
  REQUIRE(m["status"] == "succeeded");
  CHECK(m["metrics"]["coverage"].get<double>() >= 0.94);
  CHECK(m["metrics"]["path_length_ratio"].get<double>() > 0.5);
  auto res = s.get("/api/missions/" + id + "/result.json").json();
  CHECK(res["rovers"].size() == 1);
  auto geo = s.get("/api/missions/" + id + "/result.geojson");
  CHECK(geo.status == 200);
  CHECK(geo.json()["features"].size() == 1);  // one track: no route, targets or incidents
  auto csv = s.get("/api/missions/" + id + "/result.csv");
  CHECK(csv.body.rfind("rover,move,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,elevation_m\n", 0) == 0);
  auto png = s.get("/api/missions/" + id + "/map.png");
  CHECK(png.status == 200);
  CHECK(png.body.rfind("\x89PNG", 0) == 0);
  auto tif = s.get("/api/missions/" + id + "/map.tif");
  CHECK(tif.status == 200);
  CHECK((tif.body.rfind("II*", 0) == 0 || tif.body.rfind("MM", 0) == 0));
  checkError(s.get("/api/missions/" + id + "/result.xml"), 404, "file");
}

TEST_CASE("api: runs carry their map and PDM names and a label, an ended run can be deleted") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string bytes = smallDemBytes(tmp);
  auto up = request(s.port(), "POST", "/api/maps?name=small%20site&filename=small.tif", bytes, "image/tiff");
  REQUIRE(up.status == 201);
  const std::string map = up.json()["id"];
  auto pdm = s.postJson("/api/maps/" + map + "/pdms", {{"name", "ridge"}, {"random", 2}, {"seed", 3}});
  REQUIRE(pdm.status == 201);
  json body = coverageMission(map);
  body["name"] = "first try";
  body["pdm"] = pdm.json()["id"];
  body["params"]["coverage"] = 0.2;
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  CHECK(r.json()["label"] == "first try");
  json m = s.waitFinished(id);
  CHECK(m["map_name"] == "small site");
  CHECK(m["pdm_name"] == "ridge");
  CHECK(s.get("/api/missions").json()[0]["map_name"] == "small site");

  // PATCH renames; nothing else can be changed, and the label follows the names' rule.
  auto p = request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":"transect A","version":1})", "application/json");
  CHECK(p.status == 200);
  CHECK(p.json()["label"] == "transect A");
  CHECK(s.get("/api/missions/" + id).json()["label"] == "transect A");
  checkError(request(s.port(), "PATCH", "/api/missions/" + id, R"({"status":"succeeded"})", "application/json"),
             400, "status");
  checkError(request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":7})", "application/json"), 400, "label");
  checkError(request(s.port(), "PATCH", "/api/missions/" + id, json{{"label", std::string(201, 'x')}}.dump(),
                     "application/json"), 400, "label");
  checkError(request(s.port(), "PATCH", "/api/missions/" + id, "[1]", "application/json"), 400, "body");
  checkError(request(s.port(), "PATCH", "/api/missions/nope", R"({"label":"x"})", "application/json"), 404, "id");

  // A deleted map leaves its runs, without the name.
  CHECK(request(s.port(), "DELETE", "/api/maps/" + map).status == 200);
  m = s.get("/api/missions/" + id).json();
  CHECK(m["map_name"].is_null());
  CHECK(m["pdm_name"].is_null());

  // DELETE on an ended run removes it and its files; a second DELETE finds nothing.
  REQUIRE(fs::exists(s.dir.missionDir(id)));
  REQUIRE(s.manager.stream(id) != nullptr);  // finished, kept for late subscribers
  // A label cleared is cleared in the mission file too.
  CHECK(request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":"","version":2})", "application/json").status == 200);
  CHECK_FALSE(s.get("/api/missions/" + id + "/mission.json").json().contains("name"));
  auto d = request(s.port(), "DELETE", "/api/missions/" + id);
  CHECK(d.status == 200);
  CHECK(d.json()["deleted"] == id);
  CHECK_FALSE(fs::exists(s.dir.missionDir(id)));
  CHECK(s.manager.stream(id) == nullptr);  // no WebSocket replays a deleted run
  checkError(s.get("/api/missions/" + id), 404, "id");
  checkError(s.get("/api/missions/" + id + "/result.json"), 404, "id");
  CHECK(s.get("/api/missions").json().empty());
  checkError(request(s.port(), "DELETE", "/api/missions/" + id), 404, "id");
}

TEST_CASE("api: a mission file runs the mission again, with the same result") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  json body = coverageMission(map, 30, 40);
  body["name"] = "strip";
  body["params"] = {{"coverage", 0.3}, {"pattern", "boustrophedon"}};
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string first = r.json()["id"];
  REQUIRE(s.waitFinished(first)["status"] == "succeeded");

  auto f = s.get("/api/missions/" + first + "/mission.json");
  REQUIRE(f.status == 200);
  CHECK(f.headers["Content-Disposition"].find("mission-" + first + ".json") != std::string::npos);
  json file = f.json();
  CHECK(file["format"] == "roverplan-mission");
  CHECK(file["version"] == 1);
  CHECK(file["map"] == map);
  CHECK(file["dem_sha256"].get<std::string>().size() == 64);
  CHECK(file["dem_sha256"] == s.get("/api/maps/" + map).json()["dem_sha256"]);
  CHECK(file["planner"] == "coverage");
  CHECK(file["name"] == "strip");
  CHECK(file["params"] == body["params"]);
  CHECK(file["rovers"] == body["rovers"]);

  // Posted back as it is: the same run.
  r = s.postJson("/api/missions", file);
  REQUIRE(r.status == 202);
  const std::string second = r.json()["id"];
  REQUIRE(s.waitFinished(second)["status"] == "succeeded");
  json a = s.get("/api/missions/" + first + "/result.json").json();
  json b = s.get("/api/missions/" + second + "/result.json").json();
  CHECK(a["rovers"] == b["rovers"]);
  CHECK(a["metrics"] == b["metrics"]);
  CHECK(s.get("/api/missions/" + second + "/mission.json").json()["params"] == file["params"]);

  // Its own fields are checked: other ground, a newer format, a wrong one.
  json other = file;
  other["dem_sha256"] = std::string(64, '0');
  checkError(s.postJson("/api/missions", other), 409, "dem_sha256");
  other["dem_sha256"] = "ABC";
  checkError(s.postJson("/api/missions", other), 400, "dem_sha256");
  other = file;
  other["version"] = 2;
  auto newer = s.postJson("/api/missions", other);
  checkError(newer, 400, "version");
  CHECK(newer.json()["error"]["code"] == "unsupported_version");
  other = file;
  other["format"] = "qgc-plan";
  checkError(s.postJson("/api/missions", other), 400, "format");
  checkError(s.get("/api/missions/nope/mission.json"), 404, "id");
}

TEST_CASE("api: a coverage mission under localisation error streams and exports true and believed tracks") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  json body = coverageMission(map);
  body["params"] = {{"odometry_noise", -1}};
  checkError(s.postJson("/api/missions", body), 400, "params.odometry_noise");
  body["params"] = {{"coverage", 0.2}, {"odometry_noise", 5}, {"heading_noise", 1.0},
                    {"loop_closure", true}, {"noise_seed", 3}};
  body["pace"] = 3000;
  const std::string id = s.postJson("/api/missions", body).json()["id"];
  auto frames = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  REQUIRE(frames.size() >= 3);
  std::size_t believed = 0;
  for (const auto& f : frames) {
    if (f.binary) continue;
    json j = json::parse(f.data);
    if (j["type"] == "poses")
      for (const auto& r : j["rovers"]) believed += r.contains("believed") ? r["believed"].size() : 0;
  }
  CHECK(believed > 1);
  json m = s.waitFinished(id);
  // Bumps, if any, are warnings: completed_with_warnings.
  REQUIRE((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
  CHECK(m["metrics"].contains("true_coverage"));
  CHECK(m["metrics"].contains("localisation_mae_m"));
  CHECK(m["metrics"]["localisation_mae_m"].get<double>() > 0);
  auto res = s.get("/api/missions/" + id + "/result.json").json();
  REQUIRE(res["rovers"].size() == 1);
  CHECK(res["rovers"][0]["believed_path"].size() == res["rovers"][0]["path"].size());
  CHECK(res["series"].contains("true_coverage_vs_moves"));
  CHECK(res["series"].contains("localisation_error_m_rover_0"));
  auto geo = s.get("/api/missions/" + id + "/result.geojson").json();
  std::size_t bumps = 0;
  for (const auto& i : res["incidents"]) bumps += i["kind"] == "bump";
  REQUIRE(geo["features"].size() == 2 + bumps);  // both tracks, then the bumps as incidents
  CHECK(geo["features"][0]["properties"]["track"] == "true");
  CHECK(geo["features"][1]["properties"]["track"] == "believed");
  auto csv = s.get("/api/missions/" + id + "/result.csv");
  CHECK(csv.body.rfind("rover,move,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,elevation_m,"
                        "believed_x_m,believed_y_m\n", 0) == 0);
  // A late joiner gets both trails whole in the snapshot.
  auto late = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  REQUIRE(!late.empty());
  json snap = json::parse(late[0].data);
  CHECK(snap["rovers"][0]["believed_trail"].size() > 1);
  CHECK(snap["rovers"][0]["trail"].size() > 1);
}

TEST_CASE("api: two WebSocket clients see the same final state, a late joiner replays it") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  json body = coverageMission(map);
  body["pace"] = 1500;  // steps per second: about two seconds of live mission
  body["params"] = {{"coverage", 0.1}};
  const std::string id = s.postJson("/api/missions", body).json()["id"];
  std::vector<test::WsFrameSeen> a, b;
  std::thread ta([&] { a = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream"); });
  std::thread tb([&] { b = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream"); });
  ta.join();
  tb.join();
  for (auto* frames : {&a, &b}) {
    REQUIRE(frames->size() >= 3);
    json first = json::parse(frames->front().data);
    CHECK(first["type"] == "snapshot");
    json last = json::parse(frames->back().data);
    CHECK(last["type"] == "done");
    CHECK(last["status"] == "succeeded");
    bool sawGrid = false;
    int poses = 0;
    for (const auto& f : *frames) {
      sawGrid |= f.binary;
      if (!f.binary && json::parse(f.data)["type"] == "poses") ++poses;
    }
    CHECK(sawGrid);
    // Frame kinds take turns: trails stream during the run, not only at the end.
    CHECK(poses > 1);
  }
  CHECK(json::parse(a.back().data)["metrics"] == json::parse(b.back().data)["metrics"]);
  // After the end: snapshot, the full final grid, done.
  auto late = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  REQUIRE(late.size() == 3);
  CHECK(json::parse(late[0].data)["status"] == "succeeded");
  CHECK(late[1].binary);
  CHECK(json::parse(late[2].data)["metrics"] == json::parse(a.back().data)["metrics"]);
  CHECK(request(s.port(), "GET", "/api/missions/nope/stream").status == 404);
}

TEST_CASE("api: DELETE cancels a running mission promptly, a full queue answers 429") {
  TempDir tmp;
  auto o = options();
  o.workers = 1;
  o.queue = 1;
  ApiServer s(tmp.str("data"), o);
  const std::string map = s.defaultMap();
  json slow = coverageMission(map);
  slow["pace"] = 20;
  slow["params"] = {{"coverage", 1.0}};
  const std::string running = s.postJson("/api/missions", slow).json()["id"];
  s.waitStarted(running);
  const std::string waiting = s.postJson("/api/missions", slow).json()["id"];
  checkError(s.postJson("/api/missions", slow), 429, "");
  // Promptly: the paced mission (minutes to its goal) ends cancelled, not by reaching it.
  CHECK(request(s.port(), "DELETE", "/api/missions/" + running).status == 202);
  CHECK(s.waitFinished(running)["status"] == "cancelled");
  CHECK(request(s.port(), "DELETE", "/api/missions/" + waiting).status == 202);
  CHECK(s.waitFinished(waiting)["status"] == "cancelled");
}

TEST_CASE("api: with a token every /api route but health needs it") {
  TempDir tmp;
  auto o = options();
  o.http.token = "s3cret";
  ApiServer s(tmp.str("data"), o);
  CHECK(s.get("/api/health").status == 200);
  checkError(s.get("/api/maps"), 401, "authorization");
  auto ok = request(s.port(), "GET", "/api/maps", "", "", {{"Authorization", "Bearer s3cret"}});
  CHECK(ok.status == 200);
  CHECK(request(s.port(), "GET", "/api/maps", "", "", {{"Authorization", "Bearer wrong"}}).status == 401);
}

TEST_CASE("api: maps, PDMs and finished missions survive a restart, running ones are interrupted") {
  TempDir tmp;
  std::string map, pdm, done;
  {
    ApiServer s(tmp.str("data"), options());
    map = s.defaultMap();
    pdm = s.postJson("/api/maps/" + map + "/pdms", {{"random", 4}}).json()["id"];
    done = s.postJson("/api/missions", coverageMission(map)).json()["id"];
    REQUIRE(s.waitFinished(done)["status"] == "succeeded");
  }
  {
    ApiServer s(tmp.str("data"), options());
    CHECK(s.get("/api/maps").json().size() == 1);  // the default map is not made twice
    CHECK(s.get("/api/maps/" + map + "/pdms/" + pdm).status == 200);
    json m = s.get("/api/missions/" + done).json();
    CHECK(m["status"] == "succeeded");
    CHECK(s.get("/api/missions/" + done + "/result.geojson").status == 200);
    auto replay = test::readAllFrames(s.port(), "/api/missions/" + done + "/stream");
    REQUIRE(replay.size() == 3);
    CHECK(json::parse(replay[2].data)["metrics"] == m["metrics"]);
  }
}

TEST_CASE("api: folders a crash left without a database row are swept at start-up") {
  TempDir tmp;
  std::string map;
  {
    ApiServer s(tmp.str("data"), options());
    map = s.defaultMap();
    CHECK(s.orphans == 0);
  }
  // As if the server died after committing a map's files but before inserting its row.
  fs::create_directories(tmp.path / "data" / "maps" / "0123456789abcdef");
  std::ofstream(tmp.path / "data" / "maps" / "0123456789abcdef" / "dem.tif") << "half";
  fs::create_directories(tmp.path / "data" / "pdms" / "fedcba9876543210");
  ApiServer s(tmp.str("data"), options());
  CHECK(s.orphans == 2);
  CHECK_FALSE(fs::exists(tmp.path / "data" / "maps" / "0123456789abcdef"));
  CHECK(fs::exists(tmp.path / "data" / "maps" / map));  // the real map stays
  CHECK(s.get("/api/maps").json().size() == 1);
}

TEST_CASE("api: a team-search mission with a PDM streams the route and paths, and exports") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  auto pdm = s.postJson("/api/maps/" + map + "/pdms", {{"random", 4}, {"seed", 5}});
  REQUIRE(pdm.status == 201);
  const std::string pdmId = pdm.json()["id"];
  json body{{"map", map},
            {"pdm", pdmId},
            {"planner", "team-search"},
            {"rovers", {{{"x", 70}, {"y", 70}, {"heading", 0}}, {{"x", 73}, {"y", 70}, {"heading", 90}}}},
            {"params", {{"targets", 4}}}};
  // Bad input is refused before queueing, naming the field.
  json bad = body;
  bad["params"]["targets"] = 0;
  checkError(s.postJson("/api/missions", bad), 400, "params.targets");
  bad = body;
  bad["rovers"][1]["x"] = 70.3;  // closer than the safety distance
  checkError(s.postJson("/api/missions", bad), 400, "rovers[1]");
  bad = body;
  bad["pdm"] = "nope";
  checkError(s.postJson("/api/missions", bad), 400, "pdm");

  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  auto frames = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  json m = s.waitFinished(id, 120);
  // Ran to its end; with warnings (e.g. ground out of the team's reach) the status says so and the
  // message says what (issue 10: honest outcomes).
  MESSAGE(m["status"].get<std::string>() << ": " << m["message"].get<std::string>());
  REQUIRE((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
  CHECK((m["status"] == "succeeded") == (m["metrics"]["warnings"] == 0));
  if (m["status"] == "completed_with_warnings") CHECK_FALSE(m["message"].get<std::string>().empty());
  CHECK(m["metrics"]["collisions"] == 0);
  CHECK(m["metrics"]["targets"] == 4);
  CHECK(m["metrics"]["accumulated_probability"].get<double>() > 0);
  bool sawRoute = false, sawPath = false, sawGrid = false;
  json lastReplay;
  for (const auto& f : frames) {
    if (f.binary) {
      sawGrid = true;
      continue;
    }
    json j = json::parse(f.data);
    // Team progress in words (issue 13): planning counted in legs, the replay on the mission clock.
    if (j["type"] == "progress" && j.value("phase", "") == "planning") {
      CHECK(j["legs_done"].get<int>() <= j["legs_total"].get<int>());
      CHECK(j["legs_total"] == 8);  // 2 rovers × 4 targets
    }
    if (j["type"] == "progress" && j.value("phase", "") == "replay") {
      CHECK(j["mission_time_s"].get<double>() <= j["mission_end_s"].get<double>());
      lastReplay = j;
    }
    if (j["type"] == "overlay") {
      sawRoute |= j.contains("route") && j["route"].size() == 5;
      sawPath |= !j["paths"].empty();
    }
    if (j["type"] == "snapshot" && j.contains("route")) sawRoute |= j["route"].size() == 5;
  }
  CHECK(sawRoute);
  CHECK(sawPath);
  CHECK(sawGrid);
  REQUIRE(lastReplay.is_object());
  CHECK(lastReplay["mission_time_s"].get<double>() == doctest::Approx(lastReplay["mission_end_s"].get<double>()).epsilon(0.01));
  CHECK(lastReplay["mission_end_s"].get<double>() / 60 ==
        doctest::Approx(m["metrics"]["mission_time_min"].get<double>()).epsilon(0.02));
  // The search grid of 5 m cells over the 150 m map.
  json first = json::parse(frames.front().data);
  REQUIRE(first["grid"].is_object());
  CHECK(first["grid"]["rows"] == 30);
  auto res = s.get("/api/missions/" + id + "/result.json").json();
  CHECK(res["rovers"].size() == 2);
  CHECK(res["overlays"][0]["key"] == "route");
  // Attitude against mission time, per rover, with the mission's own limit.
  REQUIRE(res["series"].contains("pitch_deg_rover_1"));
  const json& pitch = res["series"]["pitch_deg_rover_1"];
  CHECK(pitch["x_label"] == "time (s)");
  CHECK(pitch["x"].size() == pitch["y"].size());
  CHECK(pitch["x"].size() > 10);
  CHECK(res["series"].contains("roll_deg_rover_0"));
  // Speed and drive energy on the same clock (the page's charts synced to the replay).
  for (const char* key : {"speed_mps_rover_0", "energy_j_rover_1"}) {
    REQUIRE(res["series"].contains(key));
    CHECK(res["series"][key]["x"][1] == pitch["x"][1]);
  }
  CHECK(res["series"]["energy_j_rover_1"]["y"].back().get<double>() ==
        doctest::Approx(res["rovers"][1]["metrics"]["energy_j"].get<double>()));
  CHECK(res["metrics"]["energy_j"].get<double>() > 0);
  // Every incident says when and where.
  for (const auto& i : res["incidents"]) {
    CHECK(i["time_s"].is_number());
    CHECK(i["x"].is_number());
    CHECK(i["y"].is_number());
  }
  CHECK(res["metrics"]["attitude_limit_deg"].get<double>() == doctest::Approx(15));
  CHECK(res["incidents"].is_array());
  // The GeoJSON: both tracks, the route, every target with its status and every incident.
  const json geo = s.get("/api/missions/" + id + "/result.geojson").json();
  std::map<std::string, std::size_t> kinds;
  for (const auto& f : geo["features"]) ++kinds[f["properties"]["layer"].get<std::string>()];
  CHECK(kinds["track"] == 2);
  CHECK(kinds["route"] == 1);
  REQUIRE(res["targets"].size() == 4);
  CHECK(kinds["target"] == 4);
  CHECK(kinds["incident"] == res["incidents"].size());
  for (const auto& t : res["targets"])
    CHECK(t["legs_reached"].get<int>() + t["legs_short"].get<int>() + t["legs_skipped"].get<int>() +
              t["legs_no_slot"].get<int>() == 2);
  auto csv = s.get("/api/missions/" + id + "/result.csv");
  CHECK(csv.body.rfind("rover,time_s,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,speed_m_s,elevation_m\n", 0) == 0);
  // A late joiner gets the overlays in its snapshot.
  auto late = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  CHECK(json::parse(late[0].data)["route"].size() == 5);
}

namespace {

// A Mars DEM in an equirectangular CRS true at the equator, placed at 30° N: its 1 m projected
// pixels are 0.866 × 1 m on the ground, so its cells are not square (issue 11). Flat, with one
// 1.04 m spike (46° to its neighbours) at row 20, col 20.
std::string marsEquirectangularBytes(const TempDir& tmp) {
  Raster<float> z(GridGeometry{40, 60, 1.0, 1.0}, 0.0f);
  z(20, 20) = 1.04f;
  z.geo.valid = true;
  const double y0 = 3396190.0 * 30.0 * std::numbers::pi / 180.0;
  z.geo.geotransform = {0, 1, 0, y0 + 40, 0, -1};
  z.geo.crsWkt =
      "PROJCS[\"Mars equirectangular\",GEOGCS[\"Mars 2000\",DATUM[\"D_Mars_2000\",SPHEROID["
      "\"Mars_2000_IAU_IAG\",3396190,0]],PRIMEM[\"Reference_Meridian\",0],UNIT[\"degree\","
      "0.0174532925199433]],PROJECTION[\"Equirectangular\"],PARAMETER[\"standard_parallel_1\",0],"
      "PARAMETER[\"central_meridian\",0],PARAMETER[\"false_easting\",0],PARAMETER["
      "\"false_northing\",0],UNIT[\"metre\",1]]";
  const std::string path = tmp.str("mars.tif");
  maps::writeGeoTiff(path, z);
  return readBytes(path);
}

}  // namespace

TEST_CASE("api: coverage on an uploaded DEM with non-square pixels, per-map defaults, one start check") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  auto up = request(s.port(), "POST", "/api/maps?name=mars&filename=mars.tif", marsEquirectangularBytes(tmp), "image/tiff");
  REQUIRE(up.status == 201);
  const std::string map = up.json()["id"];
  CHECK(up.json()["cell_size_m"].get<double>() == doctest::Approx(0.866).epsilon(0.001));
  // The defaults that come from the map: its own cell (the longer side) and Mars gravity.
  json planners = s.get("/api/planners?map=" + map).json();
  json coverage;
  for (const auto& p : planners)
    if (p["name"] == "coverage") coverage = p;
  REQUIRE(coverage.is_object());
  CHECK(coverage["map_defaults"]["body"] == "mars");
  CHECK(coverage["map_defaults"]["coverage_cell"] == 1.0);
  CHECK(coverage["map_defaults"]["gravity"] == 3.71);
  for (const auto& info : coverage["params"]) {
    if (info["key"] == "coverage_cell") CHECK(info["default"] == 1.0);
    if (info["key"] == "gravity") CHECK(info["default"] == 3.71);
  }
  checkError(s.get("/api/planners?map=nope"), 404, "map");

  // Default parameters run (before: 400 "coverage cells must be square and positive").
  json body = coverageMission(map, 5.5, 5.5);
  body["params"] = json::object();
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  json m = s.waitFinished(r.json()["id"]);
  REQUIRE(m["status"] == "succeeded");
  CHECK(m["metrics"]["gravity_m_s2"] == 3.71);
  CHECK(m["metrics"]["coverage_cell_m"] == 1.0);
  CHECK(m["metrics"]["energy_j"].get<double>() > 0);
  CHECK(s.get("/api/missions/" + r.json()["id"].get<std::string>() + "/result.json").json()["assumptions"]["body"] == "mars");
  json tooFine = body;
  tooFine["params"] = {{"coverage_cell", 0.001}};
  checkError(s.postJson("/api/missions", tooFine), 400, "params.coverage_cell");

  // The spike's cell (local x = 20·0.866 + 0.433, y = 19.5) is refused alike by every planner.
  std::string code;
  for (const char* planner : {"coverage", "team-search", "hybrid"}) {
    CAPTURE(planner);
    json bad{{"map", map}, {"planner", planner}, {"rovers", {{{"x", 17.75}, {"y", 19.5}, {"heading", 0}}}}};
    auto e = s.postJson("/api/missions", bad);
    checkError(e, 400, "rovers[0]");
    CHECK(e.json()["error"]["message"] == "rovers[0]: start is on impassable ground (a slope of 15° or more)");
    if (code.empty()) code = e.json()["error"]["code"];
    CHECK(e.json()["error"]["code"] == code);
  }
}

// Issue 27: incidents reach the live stream as they are found, not only in result.json at the
// end. A team mission on the default map with tight limits (legs under a 5° attitude check end
// short; samples pass a 2° exceedance limit), its replay paced to 2 steps a second so it is still
// running for a long while: the first incident frame must come while the mission runs, before
// any done frame. A second, unpaced run: the list the stream ends with is result.json's.
TEST_CASE("api: a team mission streams its incidents while it runs, ending with result.json's list") {
  namespace beast = rover::test::beast;
  namespace net = rover::test::net;
  using rover::test::tcp;
  using rover::test::kHangDeadline;
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  json body{{"map", s.defaultMap()},
            {"planner", "team-search"},
            {"rovers", {{{"x", 40}, {"y", 40}, {"heading", 0}}, {{"x", 46}, {"y", 40}, {"heading", 0}}}},
            {"params", {{"targets", 4}, {"attitude_limit", 5}, {"exceedance_limit", 2}}},
            {"pace", 2}};
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  {
    net::io_context ioc;
    beast::websocket::stream<beast::tcp_stream> ws(ioc);
    beast::get_lowest_layer(ws).expires_after(kHangDeadline);
    beast::get_lowest_layer(ws).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), s.port()));
    ws.read_message_max(256ull << 20);
    ws.handshake("127.0.0.1", "/api/missions/" + id + "/stream");
    json live;  // the first incident frame, or the snapshot if it already held some
    for (;;) {
      beast::flat_buffer b;
      ws.read(b);  // throws if the stream closes first: the mission ended with no live incident
      if (ws.got_binary()) continue;
      json j = json::parse(beast::buffers_to_string(b.data()));
      REQUIRE(j["type"] != "done");
      if (j["type"] == "incidents" || (j["type"] == "snapshot" && !j["incidents"].empty())) {
        live = j;
        break;
      }
    }
    // The mission is still running (its replay paced for minutes) when the incident arrives.
    CHECK(s.status(id) == "running");
    const json& list = live["incidents"];
    REQUIRE(!list.empty());
    for (const auto& i : list) {
      CHECK(i.contains("kind"));
      CHECK(i["note"].is_string());
      // Every exceedance note names the limit hit with its value and the angle reached.
      if (i["kind"] == "exceedance") {
        CHECK(i["note"].get<std::string>().find("over exceedance_limit 2.0°") != std::string::npos);
        CHECK(i["max_angle_deg"].get<double>() > 2.0);
      }
    }
    MESSAGE("first live incident: " << list[0].dump());
  }
  CHECK(request(s.port(), "DELETE", "/api/missions/" + id).status == 202);
  s.waitFinished(id);

  body["pace"] = 0;
  r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id2 = r.json()["id"];
  auto frames = test::readAllFrames(s.port(), "/api/missions/" + id2 + "/stream", std::chrono::duration_cast<std::chrono::seconds>(kHangDeadline));
  s.waitFinished(id2);
  json streamed = json::array();
  bool complete = false, sawDone = false;
  for (const auto& f : frames) {
    if (f.binary) continue;
    json j = json::parse(f.data);
    if (j["type"] == "snapshot") streamed = j["incidents"], complete = j["incidents_complete"];
    if (j["type"] == "done") sawDone = true;
    if (j["type"] != "incidents") continue;
    CHECK_FALSE(sawDone);
    json next(streamed.begin(), streamed.begin() + std::min<std::size_t>(j["from"].get<std::size_t>(), streamed.size()));
    for (const auto& i : j["incidents"]) next.push_back(i);
    streamed = std::move(next);
    complete = j["complete"];
  }
  CHECK(complete);
  auto res = s.get("/api/missions/" + id2 + "/result.json").json();
  CHECK(res["incidents"].size() > 0);
  CHECK(streamed == res["incidents"]);
}
