// The mission area over loopback (issue 24): a mission with `area` on a generated map plans in the
// area's window and reports in the map's frame (trajectories inside the area, result.json's area
// and planning_window, the mission file carrying the area); bad areas, and a map too big to plan
// whole without one, are 400s naming `area`.
#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "api_server.hpp"
#include "core/grid/geometry.hpp"
#include "maps/dem_io.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::TempDir;
using nlohmann::json;

namespace {

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A 400 × 300 m map of 1 m cells (120 000 cells), rolling ground of a few degrees: every cell
// passable, heights that differ everywhere (so a window read off by a cell would show).
std::string uploadRollingMap(ApiServer& s, const TempDir& tmp) {
  Raster<float> z(GridGeometry{300, 400, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 300; ++r)
    for (int c = 0; c < 400; ++c) z(r, c) = static_cast<float>(2 * std::sin(c / 25.0) + 1.5 * std::cos(r / 30.0) + 0.01 * c);
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100300, 0, -1};
  z.geo.crsWkt = "EPSG:32633";
  maps::writeGeoTiff(tmp.str("rolling.tif"), z);
  auto up = s.post("/api/maps?name=rolling&filename=rolling.tif", readBytes(tmp.str("rolling.tif")),
                   "application/octet-stream");
  REQUIRE(up.status == 201);
  return up.json()["id"];
}

test::ApiServerOptions options() {
  test::ApiServerOptions o;
  o.workers = 2;
  o.defaultMap = false;
  o.http.maxUploadBytes = 64ull << 20;
  return o;
}

}  // namespace

TEST_CASE("mission area api: bad areas and a map too big to plan whole are 400s naming area") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = uploadRollingMap(s, tmp);
  const json rovers = {{{"x", 220}, {"y", 170}, {"heading", 0}}};
  auto post = [&](const json& area) {
    json m{{"map", map}, {"planner", "coverage"}, {"rovers", rovers}, {"area", area}};
    return s.postJson("/api/missions", m);
  };
  checkError(post(json{{"bbox", {200, 150, 500, 210}}}), 400, "invalid_field", "area");  // off the map (400 m)
  checkError(post(json{{"bbox", {200, 150, 201, 210}}}), 400, "invalid_field", "area");  // 1 cell wide
  checkError(post(json{{"bbox", {260, 150, 200, 210}}}), 400, "invalid_field", "area.bbox");  // x1 < x0
  checkError(post(json{{"bbox", {200, 150, 260}}}), 400, "invalid_field", "area.bbox");
  checkError(post(json{{"bbox", {200, "NaN", 260, 210}}}), 400, "invalid_field", "area.bbox[1]");
  checkError(post(json{{"bbox", {200, 1e300, 260, 210}}}), 400, "invalid_field", "area.bbox[1]");
  checkError(post(json{{"polygon", {{200, 150}, {260, 150}}}}), 400, "invalid_field", "area.polygon");
  checkError(post(json{{"polygon", {{200, 150}, {260, 150}, {230}}}}), 400, "invalid_field", "area.polygon[2]");
  checkError(post(json{{"polygon", {{200, 150}, {230, 180}, {260, 210}}}}), 400, "invalid_field", "area");  // no surface
  checkError(post(json{{"circle", 5}}), 400, "invalid_field", "area");
  checkError(post(json{{"bbox", {200, 150, 260, 210}}, {"polygon", json::array()}}), 400, "invalid_field", "area");
  checkError(post("everywhere"), 400, "invalid_field", "area");
  // A rover outside the area.
  json outside{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 20}, {"y", 20}}}},
               {"area", {{"bbox", {200, 150, 260, 210}}}}};
  checkError(s.postJson("/api/missions", outside), 400, "invalid_field", "rovers[0]");
  // Over the whole-map size a mission without an area is refused, saying why and what to give.
  s.ctx.wholeMapCells = 100'000;
  json whole{{"map", map}, {"planner", "coverage"}, {"rovers", rovers}};
  auto r = s.postJson("/api/missions", whole);
  checkError(r, 400, "missing_field", "area");
  const std::string message = r.json()["error"]["message"];
  CHECK(message.find("400 x 300 cells") != std::string::npos);
  CHECK(message.find("bbox") != std::string::npos);
  // ... and with one it is accepted.
  CHECK(post(json{{"bbox", {200, 150, 260, 210}}}).status == 202);
}

TEST_CASE("mission area api: coverage and team missions in an area report in the map's frame, inside it") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = uploadRollingMap(s, tmp);
  s.ctx.wholeMapCells = 100'000;  // this map plans only in an area
  const json box{{"bbox", {200, 150, 240, 190}}};
  const Polygon boxPolygon{{{200, 150}, {240, 150}, {240, 190}, {200, 190}}};
  const json kite{{"polygon", {{205, 155}, {245, 160}, {240, 200}, {210, 195}, {205, 155}}}};
  const Polygon kitePolygon{{{205, 155}, {245, 160}, {240, 200}, {210, 195}}};
  json cov{{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 220.5}, {"y", 170.5}, {"heading", 0}}}},
           {"params", {{"coverage", 0.9}}}, {"area", kite}};
  json team{{"map", map}, {"planner", "team-search"},
            {"rovers", {{{"x", 215}, {"y", 165}, {"heading", 0}}, {{"x", 215}, {"y", 172}, {"heading", 0}}}},
            {"params", {{"targets", 6}}}, {"area", box}};
  std::vector<std::string> ids;
  for (const json& body : {cov, team}) {
    auto r = s.postJson("/api/missions", body);
    REQUIRE(r.status == 202);
    ids.push_back(r.json()["id"]);
  }
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const json m = s.waitFinished(ids[k], 180);
    MESSAGE(m["planner"].get<std::string>() << ": " << m["status"].get<std::string>() << " " << m["message"].get<std::string>());
    REQUIRE((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
    const json result = s.get("/api/missions/" + ids[k] + "/result.json").json();
    const Polygon& area = k == 0 ? kitePolygon : boxPolygon;
    int points = 0;
    for (const auto& r : result["rovers"])
      for (const auto& p : r["path"]) {
        CHECK(insidePolygon(area, {p[0].get<double>(), p[1].get<double>()}));
        ++points;
      }
    CHECK(points > 20);
    // Where it was planned: the area's bounding box plus the 4-cell margin.
    CHECK(result["area"] == (k == 0 ? json{{"polygon", {{205, 155}, {245, 160}, {240, 200}, {210, 195}}}} : box));
    const json& w = result["planning_window"];
    const double x0 = k == 0 ? 201 : 196, y0 = k == 0 ? 151 : 146;
    CHECK(w["origin"][0].get<double>() == doctest::Approx(x0));
    CHECK(w["origin"][1].get<double>() == doctest::Approx(y0));
    CHECK(w["cols"] == (k == 0 ? 48 : 48));
    CHECK(w["rows"] == (k == 0 ? 53 : 48));
    if (k == 1) {
      for (const auto& t : result["targets"]) CHECK(insidePolygon(area, {t["x"].get<double>(), t["y"].get<double>()}));
      CHECK(result["metrics"]["collisions"] == 0);
    }
    // The mission file carries the area.
    const json file = s.get("/api/missions/" + ids[k] + "/mission.json").json();
    CHECK(file["area"] == (k == 0 ? kite : box));
    // The CSV's heights are the map's under each point (read in the window, placed by its origin).
    const std::string csv = s.get("/api/missions/" + ids[k] + "/result.csv").body;
    std::istringstream lines(csv);
    std::string header, first;
    std::getline(lines, header);
    std::getline(lines, first);
    CHECK(header.find("elevation_m") != std::string::npos);
    CHECK(first.find(",,") == std::string::npos);  // every column known, elevation included
  }
}
