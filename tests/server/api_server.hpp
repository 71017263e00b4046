#pragma once
// In-process fixtures for the server tests: a scratch directory, the whole API on a data dir as
// `roverplan serve` builds it (on an ephemeral loopback port), and the checks on the project's
// error shape. The HTTP client itself is in test_client.hpp.
#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/planning/planner.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/routes.hpp"
#include "server/http/http_server.hpp"
#include "server/missions/mission_manager.hpp"
#include "server/missions/mission_memory.hpp"
#include "test_client.hpp"
#include "tests/wait_until.hpp"

namespace rover::test {

// A fresh directory under the system temp dir, removed with everything in it. The name carries
// the pid and a per-process counter, so parallel test processes and successive fixtures never meet.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static std::atomic<int> counter{0};
    path = std::filesystem::temp_directory_path() /
           ("roverplan-test-" + std::to_string(::getpid()) + "-" + std::to_string(++counter));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string str(const std::string& sub) const { return (path / sub).string(); }
};

// Where the test servers differ. `http` is the HttpServer's config; start() overrides its port
// (0, ephemeral), uploadDir (the data dir's tmp) and logRequests (off) whatever is set here.
struct ApiServerOptions {
  unsigned workers = 1;        // mission worker threads
  std::size_t queue = 8;       // missions that may wait
  std::uint64_t memoryBudget = missions::defaultMissionMemoryBudget();
  bool defaultMap = true;      // create the synthetic default map, as serve does
  bool start = true;           // false: add test routes to `router`, then call start()
  // Maps of at least this many cells are stored raw first, their COG written in the background.
  std::int64_t backgroundCells = api::MapCatalog::kDefaultBackgroundCells;
  // Maps over this many cells get their full-size layer files band by band (or 413).
  std::int64_t wholeLayerCells = api::MapCatalog::kDefaultWholeLayerCells;
  http::ServerConfig http{};
};

// The whole API on a data dir, as `roverplan serve` builds it minus the signal handling: the
// startup recovery (unfinished missions marked interrupted, orphan map / PDM dirs swept), the
// default map, the routes, and an HttpServer on 127.0.0.1.
struct ApiServer {
  store::DataDir dir;
  store::Database db;
  api::MapCatalog maps;
  PlannerRegistry planners = makeBuiltinRegistry();
  missions::MissionManager manager;
  http::Router router;
  api::ApiContext ctx;
  std::unique_ptr<http::HttpServer> server;
  http::ServerConfig config;
  int interrupted = 0;  // what the startup recovery found
  int orphans = 0;

  explicit ApiServer(const std::string& data, const ApiServerOptions& o = {})
      : dir(data),
        db((dir.cleanTmp(), dir.databasePath())),
        maps(db, dir),
        manager(db, dir, planners, o.workers, o.queue, o.memoryBudget),
        ctx{db, dir, maps, manager, planners},
        config(o.http) {
    maps.setBackgroundCells(o.backgroundCells);
    maps.setWholeLayerCells(o.wholeLayerCells);
    interrupted = db.markUnfinishedInterrupted();
    orphans = maps.sweepOrphans();
    if (o.defaultMap) maps.ensureDefaultMap();
    api::addApiRoutes(router, ctx);
    maps.resumeCompressions();  // after the routes, which set the callback its jobs call
    if (o.start) start(config);
  }
  ~ApiServer() {
    if (server) server->stop();
    maps.compressor().stop();  // before ctx, which its callback uses
    manager.stop();
  }
  ApiServer(const ApiServer&) = delete;
  ApiServer& operator=(const ApiServer&) = delete;

  void start(http::ServerConfig c) {
    c.port = 0;
    c.uploadDir = dir.tmpDir();
    c.logRequests = false;
    config = c;
    server = std::make_unique<http::HttpServer>(c, router);
    server->start();
  }
  void start() { start(config); }

  unsigned short port() const { return server->port(); }
  HttpResult get(const std::string& target) { return request(port(), "GET", target); }
  HttpResult post(const std::string& target, const std::string& body,
                  const std::string& type = "application/json") {
    return request(port(), "POST", target, body, type);
  }
  HttpResult postJson(const std::string& target, const nlohmann::json& j) {
    return request(port(), "POST", target, j.dump(), "application/json");
  }
  std::string defaultMap() { return get("/api/maps").json()[0]["id"]; }
  std::string status(const std::string& id) { return get("/api/missions/" + id).json()["status"]; }
  // Waits until the mission has a final status and its worker has let it go (its result stored,
  // or never to be: a cancelled mission is final before its partial result is stored) and returns
  // its state; FAILs on a hang (`seconds` raises the hang deadline for a long mission, never
  // lowers it).
  nlohmann::json waitFinished(const std::string& id, double seconds = 0) {
    nlohmann::json m;
    waitUntil(
        [&] {
          m = get("/api/missions/" + id).json();
          const std::string s = m["status"];
          return s != "queued" && s != "running" && m["result"] != "pending";
        },
        std::max(kHangDeadline, std::chrono::milliseconds(static_cast<long>(seconds * 1000))),
        "mission " + id + " to finish");
    return m;
  }
  // Waits until the mission has left the queue (running or already over).
  void waitStarted(const std::string& id) {
    waitUntil([&] { return status(id) != "queued"; }, "mission " + id + " to start");
  }
};

// An answer in the project's error shape {"error":{"code","message","field"}}; returns its field
// ("" when absent: the error is not about one field).
inline std::string errorField(const HttpResult& r) {
  const nlohmann::json j = r.json();
  REQUIRE(j.contains("error"));
  CHECK(j["error"].contains("code"));
  CHECK(j["error"].contains("message"));
  return j["error"].value("field", std::string());
}

// `status`, the error shape, and the offending field.
inline void checkError(const HttpResult& r, int status, const std::string& field) {
  CHECK(r.status == status);
  CHECK(errorField(r) == field);
}

// `status`, and the error's code and field exactly.
inline void checkError(const HttpResult& r, int status, const std::string& code, const std::string& field) {
  CHECK(r.status == status);
  const nlohmann::json j = r.json();
  REQUIRE(j.contains("error"));
  CHECK(j["error"].value("code", std::string()) == code);
  CHECK(j["error"].value("field", std::string()) == field);
}

// Holds each of the server's compression jobs at its start until `release` (or the compressor
// stops), so a map stays stored raw meanwhile. Declare it before the server: it outlives the
// server whose jobs it holds.
struct CompressionHold {
  std::atomic<bool> release{false};
  std::atomic<int> held{0};
  void on(ApiServer& s) {
    s.maps.compressor().setBeforeJob([this](const std::string&, const std::function<bool()>& cancelled) {
      ++held;
      pollUntil([&] { return release.load() || cancelled(); });
    });
  }
};

}  // namespace rover::test
