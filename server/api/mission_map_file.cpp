#include "server/api/mission_map_file.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "maps/mission_map.hpp"
#include "server/http/http_types.hpp"
#include "server/missions/mission_manager.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;
using nlohmann::json;

namespace {

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<Eigen::Vector2d> points(const json& a) {
  std::vector<Eigen::Vector2d> out;
  if (a.is_array())
    for (const auto& p : a) out.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
  return out;
}

// What the picture draws, read back from the stored result (server/json/plan_json.cpp's shape).
void fromResult(const json& r, maps::MissionMapInput& in) {
  for (const auto& rover : r.value("rovers", json::array())) {
    Track t;
    t.rover = rover.value("rover", 0);
    t.points = points(rover.value("path", json::array()));
    in.tracks.push_back(std::move(t));
  }
  for (const auto& o : r.value("overlays", json::array()))
    if (o.value("key", "") == "route") in.route = points(o.value("points", json::array()));
  // Results are written by plan_json.cpp from the same name tables, so every name parses; a
  // target that did not would be drawn grey like an unreachable one, an incident's kind is not drawn.
  for (const auto& t : r.value("targets", json::array()))
    in.targets.push_back({t.value("target", 0), {t.value("x", 0.0), t.value("y", 0.0)},
                          parseEnum<TargetStatus>(t.value("status", "")).value_or(TargetStatus::Unreachable),
                          0, 0, 0, 0});
  for (const auto& i : r.value("incidents", json::array())) {
    Incident inc;
    inc.kind = parseEnum<IncidentKind>(i.value("kind", "")).value_or(IncidentKind::Collision);
    inc.rover = i.value("rover", 0);
    inc.position = {i.value("x", 0.0), i.value("y", 0.0)};
    in.incidents.push_back(std::move(inc));
  }
}

// The final coverage grid from grid.bin (a full frame: u32 type 2, rows, cols, count, then
// rows·cols states), with the coverage cell from the result's metrics. Only a planner that plans
// on a coverage grid draws it: a team's grid is its route search grid.
void coverageGrid(const fs::path& dir, const json& r, maps::MissionMapInput& in) {
  const double cell = r.value("metrics", json::object()).value("coverage_cell_m", 0.0);
  const std::string bytes = readAll(dir / "grid.bin");
  if (cell <= 0 || bytes.size() < 16) return;
  std::uint32_t head[4];
  std::memcpy(head, bytes.data(), sizeof head);
  const std::size_t n = std::size_t(head[1]) * head[2];
  if (head[0] != 2 || bytes.size() < 16 + n) return;
  in.coverageGrid = GridGeometry{static_cast<int>(head[1]), static_cast<int>(head[2]), cell, cell};
  in.coverageStates.assign(bytes.begin() + 16, bytes.begin() + 16 + static_cast<std::ptrdiff_t>(n));
}

}  // namespace

std::string missionMapFile(ApiContext& ctx, const store::MissionRecord& m, const std::string& format) {
  const fs::path dir = ctx.dir.missionDir(m.id);
  const fs::path file = dir / ("map." + format);
  if (fs::exists(file)) return file.string();
  if (!fs::exists(dir / "result.json"))
    throw ApiError(409, "not_ready", "mission " + m.id + " is " + std::string(enumName(m.status)) + ": no result yet", "id");
  if (!ctx.db.getMap(m.mapId))
    throw ApiError(409, "map_deleted", "the mission's map " + m.mapId + " was deleted: no map to draw on", "id");
  auto map = ctx.maps.get(m.mapId);
  const GridGeometry& g = map->dem.geometry();
  // A DEM over the cap is drawn resampled (the catalog's cached copy at the coarser cell).
  std::shared_ptr<const terrain::Dem> resampled;
  const terrain::Dem* dem = &map->dem;
  const int side = std::max(g.rows, g.cols);
  if (side > maps::kMissionMapMaxSide) {
    const double cell = std::max(g.cellWidth, g.cellHeight) * side / (maps::kMissionMapMaxSide - 1);
    resampled = ctx.maps.demAtCell(m.mapId, cell);
    dem = resampled.get();
  }
  const json result = json::parse(readAll(dir / "result.json"));
  maps::MissionMapInput in;
  in.dem = dem;
  in.title = "mission " + m.id + " - " + m.planner;
  fromResult(result, in);
  if (const Planner* p = ctx.planners.find(m.planner); p && p->specs().ground == Ground::CoverageGrid)
    coverageGrid(dir, result, in);
  in.zones = missions::keepOutZones(m.spec);
  const maps::MissionMap picture = maps::renderMissionMap(in);
  const std::vector<std::uint8_t> bytes =
      format == "png" ? maps::encodePng(picture.image) : maps::encodeMissionMapGeoTiff(picture, g, map->dem.z.geo);
  store::DataDir::writeFileAtomic(file.string(), std::string(bytes.begin(), bytes.end()));
  return file.string();
}

}  // namespace rover::api
