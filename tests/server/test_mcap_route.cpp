// GET /api/missions/{id}/replay.mcap (issue 28): 404 for an unknown mission, 409 not_ready while
// it runs, the file (an attachment) once it has ended, with the counts its result says.
#include <doctest/doctest.h>

#include <string>

#include "api_server.hpp"
#include "mcap_reader.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

TEST_CASE("mcap route: 404 unknown, 409 while running, 200 with the replay after") {
  TempDir d;
  ApiServer s(d.str("data"));
  const std::string map = s.defaultMap();
  checkError(s.get("/api/missions/no-such-mission/replay.mcap"), 404, "not_found", "id");

  // Running: paced at 5 moves a second towards full coverage, it runs until cancelled.
  json slow{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 20.5}, {"y", 20.5}, {"heading", 0}}}},
            {"params", {{"frontier", false}, {"coverage", 1}}}, {"pace", 5}};
  auto r = s.postJson("/api/missions", slow);
  REQUIRE(r.status == 202);
  const std::string running = r.json()["id"];
  s.waitStarted(running);
  checkError(s.get("/api/missions/" + running + "/replay.mcap"), 409, "not_ready", "id");
  CHECK(request(s.port(), "DELETE", "/api/missions/" + running).status == 202);
  CHECK(s.waitFinished(running)["result"] == "ready");
  // Its partial result has its replay too.
  CHECK(s.get("/api/missions/" + running + "/replay.mcap").status == 200);

  json quick{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 10.5}, {"y", 10.5}, {"heading", 0}}}},
             {"params", {{"coverage", 0.5}}}};
  r = s.postJson("/api/missions", quick);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  REQUIRE(s.waitFinished(id)["status"] == "succeeded");
  auto file = s.get("/api/missions/" + id + "/replay.mcap");
  REQUIRE(file.status == 200);
  CHECK(file.headers["Content-Type"] == "application/octet-stream");
  CHECK(file.headers["Content-Disposition"].find("mission-" + id + "-replay.mcap") != std::string::npos);
  const test::McapFile m = test::readMcap(file.body);
  // The default map has a CRS: a fix per pose. Coverage: one pose per path point.
  const json result = s.get("/api/missions/" + id + "/result.json").json();
  const std::size_t points = result["rovers"][0]["path"].size();
  CHECK(m.count("/rover_0/pose") == points);
  CHECK(m.count("/rover_0/fix") == points);
  CHECK(m.count("/rover_0/telemetry") == points);
  CHECK(m.count("/map/terrain") == 1);
  CHECK(m.count("/incidents") == result["incidents"].size());
  // Served from the mission's folder, the same bytes each time.
  CHECK(s.get("/api/missions/" + id + "/replay.mcap").body == file.body);
}
