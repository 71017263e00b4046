#include "server/api/mission_map_file.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/terrain/layers.hpp"
#include "maps/mission_map.hpp"
#include "maps/value_geotiff.hpp"
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

// A planner's number parameter as the mission ran it: the request's value, else the default.
double paramOf(const Planner* planner, const json& spec, const std::string& key, double fallback) {
  const json params = spec.value("params", json::object());
  if (auto v = params.find(key); v != params.end() && v->is_number()) return v->get<double>();
  if (planner)
    for (const ParamInfo& info : planner->params())
      if (info.key == key) {
        if (const double* d = std::get_if<double>(&info.defaultValue)) return *d;
        if (const std::int64_t* i = std::get_if<std::int64_t>(&info.defaultValue)) return static_cast<double>(*i);
      }
  return fallback;
}

// The mission's values on the map's grid (`dem`: the map, or its copy resampled under the size
// cap), one band each: elevation, traversability class (at the mission's slope thresholds), the
// final grid's visits (the coverage grid, or a team's search grid of footprint cells, both
// anchored at the map's lower-left corner), and the PDM the mission searched when it had one.
std::vector<maps::ValueBand> valueBands(ApiContext& ctx, const store::MissionRecord& m, const fs::path& dir,
                                        const json& result, const terrain::Dem& dem) {
  const GridGeometry& g = dem.geometry();
  const Planner* planner = ctx.planners.find(m.planner);
  std::vector<maps::ValueBand> bands;
  bands.push_back({"elevation (m)", dem.z});
  terrain::TraversabilityParams tp;
  tp.highRiskDeg = paramOf(planner, m.spec, "high_risk_deg", tp.highRiskDeg);
  tp.impassableDeg = paramOf(planner, m.spec, "impassable_deg", tp.impassableDeg);
  {
    const Raster<std::uint8_t> classes = terrain::traversability(dem, tp, false, 1).classes;
    Raster<float> c(g, std::numeric_limits<float>::quiet_NaN());
    for (int i = 0; i < g.cellCount(); ++i)
      if (classes.at(i) != static_cast<std::uint8_t>(terrain::TerrainClass::NoData)) c.at(i) = classes.at(i);
    char name[160];
    std::snprintf(name, sizeof name, "traversability class (0 traversable, 1 high risk from %g deg, 2 impassable from %g deg)",
                  tp.highRiskDeg, tp.impassableDeg);
    bands.push_back({name, std::move(c)});
  }
  const std::string bytes = readAll(dir / "grid.bin");
  std::uint32_t head[4] = {0, 0, 0, 0};
  if (bytes.size() >= 16) std::memcpy(head, bytes.data(), sizeof head);
  const std::size_t n = std::size_t(head[1]) * head[2];
  const bool coverage = planner && planner->specs().ground == Ground::CoverageGrid;
  const double cell = coverage ? result.value("metrics", json::object()).value("coverage_cell_m", 0.0)
                               : paramOf(planner, m.spec, "footprint_m", 0.0);
  if (head[0] == 2 && n > 0 && bytes.size() >= 16 + 5 * n && cell > 0) {
    const int rows = static_cast<int>(head[1]), cols = static_cast<int>(head[2]);
    Raster<float> v(g, std::numeric_limits<float>::quiet_NaN());
    for (int r = 0; r < g.rows; ++r)
      for (int c = 0; c < g.cols; ++c) {
        const double x = (c + 0.5) * g.cellWidth, y = (g.rows - r - 0.5) * g.cellHeight;
        const int gc = static_cast<int>(std::floor(x / cell)), gr = rows - 1 - static_cast<int>(std::floor(y / cell));
        if (gc < 0 || gc >= cols || gr < 0 || gr >= rows) continue;
        std::uint32_t visits = 0;
        std::memcpy(&visits, bytes.data() + 16 + n + 4 * (std::size_t(gr) * cols + gc), 4);
        v(r, c) = static_cast<float>(visits);
      }
    char name[120];
    std::snprintf(name, sizeof name, "visits (%s grid of %g m cells)", coverage ? "coverage" : "team search", cell);
    bands.push_back({name, std::move(v)});
  }
  if (!m.pdmId.empty() && ctx.db.getPdm(m.pdmId)) {
    const auto mass = ctx.maps.pdmMass(m.pdmId);
    const GridGeometry& pg = mass->geometry;
    Raster<float> p(g, std::numeric_limits<float>::quiet_NaN());
    // The mass per cell of the map's own grid (a resampled band cell shows the map cell under its centre).
    for (int r = 0; r < g.rows; ++r)
      for (int c = 0; c < g.cols; ++c) {
        const int pr = std::min(pg.rows - 1, static_cast<int>((r + 0.5) * pg.rows / g.rows));
        const int pc = std::min(pg.cols - 1, static_cast<int>((c + 0.5) * pg.cols / g.cols));
        p(r, c) = (*mass)(pr, pc);
      }
    bands.push_back({"PDM (probability mass per map cell)", std::move(p)});
  }
  return bands;
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
  if (format == "tif") {
    // Values, not a picture (issue 27): a GIS computes with these; map.png is the picture.
    const std::vector<std::uint8_t> bytes = maps::encodeValueGeoTiff(valueBands(ctx, m, dir, result, *dem), g, map->dem.z.geo);
    store::DataDir::writeFileAtomic(file.string(), std::string(bytes.begin(), bytes.end()));
    return file.string();
  }
  maps::MissionMapInput in;
  in.dem = dem;
  in.title = "mission " + m.id + " - " + m.planner;
  fromResult(result, in);
  if (const Planner* p = ctx.planners.find(m.planner); p && p->specs().ground == Ground::CoverageGrid)
    coverageGrid(dir, result, in);
  in.zones = missions::keepOutZones(m.spec);
  const maps::MissionMap picture = maps::renderMissionMap(in);
  const std::vector<std::uint8_t> bytes = maps::encodePng(picture.image);
  store::DataDir::writeFileAtomic(file.string(), std::string(bytes.begin(), bytes.end()));
  return file.string();
}

}  // namespace rover::api
