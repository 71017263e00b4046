// Issue 14, missions and storage: memory bounded and stated (a per-mission estimate counted against
// a budget: 413 / 429 with the reason), queued missions that hold no world, and one snapshot shared
// by every WebSocket subscriber. Over loopback with an in-process server; loops bounded.
#include <doctest/doctest.h>

#include <fstream>
#include <thread>

#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "core/coverage/coverage_memory.hpp"
#include "server/missions/mission_memory.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

// The default map: 600 × 600 cells of 0.25 m (150 m square).
constexpr std::int64_t kDefaultMapCells = 600 * 600;

// A server with this memory budget for missions and room for `queue` waiting ones.
test::ApiServerOptions budgetOf(std::uint64_t budget, std::size_t queue = 8) {
  test::ApiServerOptions o;
  o.memoryBudget = budget;
  o.queue = queue;
  return o;
}

// The estimate of a coverage mission with the server's default step budget (no max_steps given).
missions::MemoryEstimate defaultStepsEstimate(std::int64_t cells, double cell, int rovers) {
  ParamSet none;
  return coverage::missionMemory(cells, cell, rovers, false, coverage::stepBudget(none, 0, cells, rovers));
}

json coverageMission(const std::string& map, double cell, double pace = 0, double goal = 0.05) {
  json j{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 20.5}, {"y", 20.5}, {"heading", 0}}}},
         {"params", {{"coverage_cell", cell}, {"coverage", goal}}}};
  if (pace > 0) j["pace"] = pace;
  return j;
}

}  // namespace

TEST_CASE("hostile missions: one mission over the memory budget is refused with 413, naming coverage_cell") {
  TempDir d;
  // The budget fits two missions on the map's own 0.25 m cells, not one on 0.16 m cells (2.4 times
  // the cells, still under the coverage grid's own cell limit): that one must be refused before its
  // world is built.
  const auto native = defaultStepsEstimate(kDefaultMapCells, 0.25, 1);
  ApiServer s(d.str("data"), budgetOf(native.bytes * 2));
  const std::string map = s.defaultMap();
  auto r = s.postJson("/api/missions", coverageMission(map, 0.16));
  checkError(r, 413, "mission_too_large", "params.coverage_cell");
  const std::string message = r.json()["error"]["message"];
  MESSAGE(message);
  // The reason states the estimate and the budget.
  CHECK(message.find(missions::formatBytes(s.manager.memoryBudget())) != std::string::npos);
  CHECK(message.find("879844 coverage cells") != std::string::npos);
  CHECK(s.manager.memoryReserved() == 0);
  CHECK(s.manager.queued() == 0);
  // The same mission on the map's cells is accepted and runs.
  auto ok = s.postJson("/api/missions", coverageMission(map, 0));
  REQUIRE(ok.status == 202);
  CHECK(s.waitFinished(ok.json()["id"])["status"] == "succeeded");
  CHECK(s.manager.memoryReserved() == 0);  // released when it finished
}

TEST_CASE("hostile missions: running + queued missions over the budget get 429 with Retry-After, cancel frees it") {
  TempDir d;
  const auto one = defaultStepsEstimate(kDefaultMapCells, 0.25, 1);
  ApiServer s(d.str("data"), budgetOf(one.bytes * 2 + one.bytes / 2));  // room for two
  const std::string map = s.defaultMap();
  const auto slow = coverageMission(map, 0.25, 5, 1.0);  // 5 steps a second: runs until cancelled
  const std::string first = s.postJson("/api/missions", slow).json()["id"];
  const std::string second = s.postJson("/api/missions", slow).json()["id"];
  CHECK(s.manager.memoryReserved() == 2 * one.bytes);
  auto refused = s.postJson("/api/missions", slow);
  checkError(refused, 429, "memory_busy", "");
  CHECK(refused.headers.count("Retry-After") == 1);
  const std::string why = refused.json()["error"]["message"];
  MESSAGE(why);
  CHECK(why.find("mission memory budget") != std::string::npos);
  CHECK(s.manager.running() + s.manager.queued() == 2);
  // Cancelling the queued one gives its share back: the next is accepted.
  CHECK(request(s.port(), "DELETE", "/api/missions/" + second).status == 202);
  CHECK(s.waitFinished(second)["status"] == "cancelled");
  CHECK(s.manager.memoryReserved() == one.bytes);
  const std::string third = s.postJson("/api/missions", slow).json()["id"];
  for (const auto& id : {first, third}) CHECK(request(s.port(), "DELETE", "/api/missions/" + id).status == 202);
  for (const auto& id : {first, third}) CHECK(s.waitFinished(id)["status"] == "cancelled");
  CHECK(s.manager.memoryReserved() == 0);
}

TEST_CASE("hostile missions: the queue stays bounded in count too, with Retry-After") {
  TempDir d;
  ApiServer s(d.str("data"), budgetOf(64ull << 30, 1));
  const std::string map = s.defaultMap();
  const auto slow = coverageMission(map, 0, 5, 1.0);
  const std::string running = s.postJson("/api/missions", slow).json()["id"];
  s.waitStarted(running);
  const std::string waiting = s.postJson("/api/missions", slow).json()["id"];
  auto full = s.postJson("/api/missions", slow);
  checkError(full, 429, "queue_full", "");
  CHECK(full.headers.count("Retry-After") == 1);
  for (const auto& id : {waiting, running}) CHECK(request(s.port(), "DELETE", "/api/missions/" + id).status == 202);
  for (const auto& id : {waiting, running}) CHECK(s.waitFinished(id)["status"] == "cancelled");
}

TEST_CASE("hostile missions: a queued mission holds its request, not its world (built when it starts)") {
  TempDir d;
  ApiServer s(d.str("data"), budgetOf(64ull << 30));
  const std::string map = s.defaultMap();
  // A second map to delete while a mission on it waits behind a slow one.
  Raster<float> z(GridGeometry{60, 60, 0.5, 0.5}, 0.0f);
  for (int r = 0; r < 60; ++r)
    for (int c = 0; c < 60; ++c) z(r, c) = 0.01f * static_cast<float>(c + r);
  const std::string path = (d.path / "flat.tif").string();
  maps::writeGeoTiff(path, z);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  auto up = request(s.port(), "POST", "/api/maps?filename=flat.tif&name=flat", bytes, "image/tiff");
  REQUIRE(up.status == 201);
  const std::string other = up.json()["id"];

  const std::string running = s.postJson("/api/missions", coverageMission(map, 0, 5, 1.0)).json()["id"];
  json waitingBody = coverageMission(other, 0);
  waitingBody["rovers"] = {{{"x", 5.2}, {"y", 5.2}, {"heading", 0}}};
  auto queued = s.postJson("/api/missions", waitingBody);
  REQUIRE(queued.status == 202);
  const std::string waiting = queued.json()["id"];
  // Its world does not exist yet: deleting the map under it makes the mission fail when a
  // worker starts it, with the reason, instead of running on a world it kept.
  REQUIRE(request(s.port(), "DELETE", "/api/maps/" + other).status == 200);
  CHECK(request(s.port(), "DELETE", "/api/missions/" + running).status == 202);
  json m = s.waitFinished(waiting);
  CHECK(m["status"] == "failed");
  CHECK(std::string(m["message"]).find("cannot build what the planner plans on") != std::string::npos);
  CHECK(s.manager.memoryReserved() == 0);
  // Its result will never come: 409 with a code that says so (not a 500, not "not ready"); its
  // mission file still names the grid it was launched on (recorded at launch, the map is gone).
  for (const char* f : {"result.json", "result.geojson", "result.csv"})
    checkError(s.get("/api/missions/" + waiting + "/" + f), 409, "no_result", "id");
  auto file = s.get("/api/missions/" + waiting + "/mission.json");
  REQUIRE(file.status == 200);
  CHECK(file.json()["dem_sha256"] == up.json()["dem_sha256"]);
}

TEST_CASE("hostile missions: every WebSocket subscriber gets the same snapshot bytes, built once") {
  TempDir d;
  ApiServer s(d.str("data"), budgetOf(64ull << 30));
  json body{{"map", s.defaultMap()}, {"planner", "coverage"}, {"params", {{"coverage", 0.3}}}, {"rovers", json::array()}};
  for (int k = 0; k < 4; ++k) body["rovers"].push_back({{"x", 20.5 + 30 * k}, {"y", 20.5}, {"heading", 0}});
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  REQUIRE(s.waitFinished(id)["status"] == "succeeded");
  auto stream = s.manager.stream(id);
  REQUIRE(stream);
  const std::uint64_t before = stream->snapshotBuilds();

  constexpr int kClients = 6;
  std::vector<std::vector<test::WsFrameSeen>> seen(kClients);
  std::vector<std::thread> clients;
  for (int k = 0; k < kClients; ++k)
    clients.emplace_back([&, k] { seen[k] = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream"); });
  for (auto& t : clients) t.join();
  for (int k = 0; k < kClients; ++k) {
    REQUIRE(seen[k].size() == 3);  // snapshot, full grid, done
    CHECK(seen[k][0].data == seen[0][0].data);
    CHECK(seen[k][1].data == seen[0][1].data);
  }
  const json snap = json::parse(seen[0][0].data);
  CHECK(snap["type"] == "snapshot");
  CHECK(snap["rovers"].size() == 4);
  CHECK(snap["rovers"][0]["trail"].size() > 1);
  CHECK(snap["status"] == "succeeded");
  CHECK(seen[0][1].binary);
  CHECK(stream->snapshotBuilds() == before + 1);  // one state, one snapshot for all six clients

  // A later client at the same state reuses it too.
  auto a = test::readAllFrames(s.port(), "/api/missions/" + id + "/stream");
  CHECK(stream->snapshotBuilds() == before + 1);
  REQUIRE(a.size() == 3);
  CHECK(a[0].data == seen[0][0].data);
}

TEST_CASE("hostile missions: a subscriber that never reads is dropped while a reading one gets every frame") {
  TempDir d;
  test::ApiServerOptions o = budgetOf(64ull << 30);
  o.http.readTimeout = 1s;  // a stuck write is given up after 1 s + 1 s per 256 KiB
  ApiServer s(d.str("data"), o);
  // 600×600 coverage cells: the snapshot's full grid alone (1.8 MB) cannot pass a 4 KiB window.
  auto r = s.postJson("/api/missions", coverageMission(s.defaultMap(), 0.25, 400, 0.02));
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  const std::string target = "/api/missions/" + id + "/stream";

  test::net::io_context ioc;
  test::beast::websocket::stream<test::tcp::socket> stuck(ioc);
  stuck.next_layer().open(test::tcp::v4());
  stuck.next_layer().set_option(test::net::socket_base::receive_buffer_size(4096));
  stuck.next_layer().connect(test::tcp::endpoint(test::net::ip::make_address("127.0.0.1"), s.port()));
  stuck.handshake("127.0.0.1", target);  // then never reads

  const auto frames = test::readAllFrames(s.port(), target, std::chrono::seconds(120));
  REQUIRE(frames.size() >= 3);
  CHECK(json::parse(frames.front().data)["type"] == "snapshot");
  CHECK(json::parse(frames.back().data)["type"] == "done");
  // The reader is gone; the stuck one is dropped at its write deadline (the stream holds its
  // subscribers weakly, so the count falls when the session ends).
  auto stream = s.manager.stream(id);
  REQUIRE(stream);
  test::waitUntil([&] { return stream->subscriberCount() == 0; }, "the stream to lose its stuck subscriber");
}

namespace {

// The mission: four rovers, frontier off and a goal of 1 (never met on a DEM, whose
// unsensed pockets count as free), so only the step budget ends it.
json neverEndingMission(const std::string& map) {
  json rovers = json::array();
  for (int k = 0; k < 4; ++k) rovers.push_back({{"x", 70.5 + 3 * k}, {"y", 70.5}, {"heading", 0}});
  return {{"map", map}, {"planner", "coverage"}, {"rovers", rovers},
          {"params", {{"frontier", false}, {"coverage", 1}}}};
}

}  // namespace

TEST_CASE("hostile missions: max_steps whose moves cannot fit the budget is refused with 413 naming it") {
  TempDir d;
  ApiServer s(d.str("data"), budgetOf(256ull << 20));
  const std::string map = s.defaultMap();
  json body = neverEndingMission(map);
  body["params"]["max_steps"] = 1e9;  // issue 22: admitted at ~60 MiB, grew to 2.46 GB
  auto r = s.postJson("/api/missions", body);
  checkError(r, 413, "mission_too_large", "params.max_steps");
  const std::string message = r.json()["error"]["message"];
  MESSAGE(message);
  CHECK(message.find("up to 1000000000 steps") != std::string::npos);
  CHECK(s.manager.memoryReserved() == 0);
  // The message says which max_steps fits; that one is admitted, within the budget, and
  // cancelling it ends it (a deadline that only catches a hang).
  const auto at = message.find("give max_steps ");
  REQUIRE(at != std::string::npos);
  const long long fits = std::stoll(message.substr(at + 15));
  CHECK(fits > 0);
  body["params"]["max_steps"] = fits;
  auto ok = s.postJson("/api/missions", body);
  REQUIRE(ok.status == 202);
  CHECK(s.manager.memoryReserved() <= s.manager.memoryBudget());
  body["params"]["max_steps"] = fits + 1;
  checkError(s.postJson("/api/missions", body), 413, "mission_too_large", "params.max_steps");
  CHECK(request(s.port(), "DELETE", "/api/missions/" + ok.json()["id"].get<std::string>()).status == 202);
  CHECK(s.waitFinished(ok.json()["id"])["status"] == "cancelled");
  CHECK(s.manager.memoryReserved() == 0);
}

TEST_CASE("hostile missions: without max_steps a mission that never meets its goal ends at the steps its estimate counts") {
  TempDir d;
  ApiServer s(d.str("data"), budgetOf(1ull << 30));
  auto r = s.postJson("/api/missions", neverEndingMission(s.defaultMap()));
  REQUIRE(r.status == 202);
  const json m = s.waitFinished(r.json()["id"], 120);
  CHECK(m["status"] == "succeeded");
  // The default coverage grid of the map keeps 40 000 cells: four moves a cell for the team of
  // four is 40 000 steps (the planner's own default would be 20 × 40 000 steps of 4 moves).
  const double cells = m["metrics"]["cells"];
  CHECK(m["metrics"]["steps"].get<double>() == std::ceil(coverage::kDefaultMovesPerCell * cells / 4));
  CHECK(m["metrics"]["moves"].get<double>() <= coverage::kDefaultMovesPerCell * cells);
  const json result = s.get("/api/missions/" + r.json()["id"].get<std::string>() + "/result.json").json();
  CHECK(result["stop_reason"] == "step_budget");
  CHECK(s.manager.memoryReserved() == 0);
}
