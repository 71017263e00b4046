#include "server/api/mission_service.hpp"

#include <sstream>

#include "core/common/error.hpp"
#include "server/api/mission_file.hpp"
#include "server/api/route_kit.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/zones_json.hpp"
#include "server/problems/problem_builder.hpp"
#include "server/store/disk_budget.hpp"
#include "core/planning/mission_area.hpp"

namespace rover::api {


namespace {

// A core Error of the request with its field qualified for the API's error mapping
// ("params.targets"); one that names no field is the body's.
[[noreturn]] void rethrowQualified(const Error& e, const std::string& prefix) {
  throw Error(e.code(), e.field().empty() ? "body" : prefix + e.field(), e.what());
}

std::string metres(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

missions::MissionJob buildMission(ApiContext& ctx, const json& body) {
  rj::MissionRequest request = rj::parseMissionRequest(body, ctx.planners, kMissionFileVersion);
  missions::MissionJob job;
  job.record.mapId = request.mapId;
  job.record.pdmId = request.pdmId;
  job.record.planner = request.planner;
  job.record.label = request.name;
  job.params = std::move(request.params);
  job.problem.rovers = std::move(request.rovers);
  job.problem.keepOut = std::move(request.keepOut);
  if (request.pace) job.pace = *request.pace;
  const Planner& planner = ctx.planners.get(job.record.planner);
  if (!ctx.db.getMap(job.record.mapId))
    throw ApiError(400, "not_found", "no map '" + rj::shown(job.record.mapId) + "'", "map");
  // Its result is charged to the map: refused now (507) when the map's budget is already full.
  ctx.dir.budget().requireRoom(store::DiskUse::Result, job.record.mapId, "map");
  // The grid the run plans on, recorded with it (its mission file names this DEM even if the
  // map is deleted or its digest computed differently later).
  const std::string digest = mapDigest(ctx, job.record.mapId);
  if (request.demSha256 && *request.demSha256 != digest)
    throw ApiError(409, "map_changed",
                   "map " + job.record.mapId + " is not the grid this mission file was planned on "
                   "(its dem_sha256 differs): upload the same DEM with the same crop and cell size, "
                   "and put that map's id in the file",
                   "dem_sha256");
  // The versions the run uses (issue 26): its PDM's now, and the zone set's its keep_out was read at.
  json used{{"pdm_version", nullptr}, {"zones_version", nullptr}};
  if (!job.record.pdmId.empty()) {
    auto p = ctx.db.getPdm(job.record.pdmId);
    if (!p || p->mapId != job.record.mapId)
      throw ApiError(400, "not_found", "no PDM '" + rj::shown(job.record.pdmId) + "' on this map", "pdm");
    used["pdm_version"] = p->version;
  }
  if (auto k = body.find("keep_out"); k != body.end() && k->is_object())
    if (auto v = k->find("version"); v != k->end() && v->is_number_unsigned()) used["zones_version"] = *v;
  // What the planner plans on, as its description says (PlannerSpecs::ground), on the map or on
  // the planning window of the mission's area (issue 24). Its memory is estimated by the planner
  // on that ground and checked against the mission budget first. The map's header only: a big
  // map is never loaded whole for a mission in an area of it.
  const MapHeader map = ctx.maps.header(job.record.mapId);
  const GridGeometry& mapGeometry = map.geometry;
  rj::checkZonesOnMap(job.problem.keepOut, mapGeometry, "keep_out");
  if (request.area) {
    try {
      checkMissionArea(*request.area, mapGeometry);
    } catch (const Error& e) {
      throw ApiError(400, "invalid_field", e.what(), "area");
    }
    for (std::size_t i = 0; i < job.problem.rovers.size(); ++i) {
      const Eigen::Vector2d p = job.problem.rovers[i].position;
      if (!insidePolygon({request.area->outline}, p))
        throw ApiError(400, "invalid_field",
                       "rover " + std::to_string(i) + " starts at (" + metres(p.x()) + ", " + metres(p.y()) +
                           ") m, outside the mission area: every rover starts inside it",
                       "rovers[" + std::to_string(i) + "]");
    }
    job.area = request.area;
    job.window = planningWindow(mapGeometry, *request.area);
  } else {
    if (static_cast<std::int64_t>(mapGeometry.rows) * mapGeometry.cols > ctx.wholeMapCells)
      throw ApiError(400, "missing_field",
                     "map " + job.record.mapId + " is " + std::to_string(mapGeometry.cols) + " x " +
                         std::to_string(mapGeometry.rows) + " cells, more than a mission plans on whole (" +
                         std::to_string(ctx.wholeMapCells) + " cells): the traversal lattice, "
                         "floods and classes would cover every cell before the rovers move. Give the "
                         "mission an area, {\"bbox\": [x0, y0, x1, y1]} or {\"polygon\": [[x, y], ...]} in the "
                         "map's local metres; it is planned at the map's full resolution",
                     "area");
    job.window = wholeMap(mapGeometry);
  }
  const int roverCount = static_cast<int>(job.problem.rovers.size());
  MapGround ground;
  try {
    ground = planner.groundOnMap(job.window.grid, job.params);
    job.memory = planner.memoryEstimate(job.window.grid, ground, roverCount, !job.record.pdmId.empty(), job.params);
  } catch (const Error& e) {
    rethrowQualified(e, "params.");
  }
  ctx.missions.admit(job.memory);
  // Built twice (here to validate, then by the worker): the request's rovers and zones, in the
  // map's frame, are kept here and moved into the window's each time.
  job.build = [&maps = ctx.maps, ground, rovers = job.problem.rovers, keepOut = job.problem.keepOut](missions::MissionJob& j) {
    std::shared_ptr<const terrain::Dem> dem;
    std::shared_ptr<const Raster<float>> pdm;
    const bool withPdm = ground.kind == Ground::DemAndPdm && !j.record.pdmId.empty();
    PlanningProblem built;
    if (j.area) {
      dem = maps.demWindow(j.record.mapId, j.window);
      const MapHeader header = maps.header(j.record.mapId);
      const auto inArea = cellsInArea(areaInWindow(*j.area, j.window), j.window.grid);
      if (withPdm)
        pdm = maps.pdmMassIn(j.record.pdmId, j.window, *dem, inArea);
      else if (ground.kind == Ground::DemAndPdm)
        pdm = std::make_shared<const Raster<float>>(problems::uniformPdm(*dem, inArea));
      built = problems::problemOnMap(ground, dem, std::move(pdm), header.body);
      built.rovers = rovers;
      built.keepOut = keepOut;
      moveIntoWindow(built.rovers, built.keepOut, j.window, *j.area);
      j.geo = header.geo;
      j.mapGrid = header.geometry;
    } else {
      dem = maps.demAtCell(j.record.mapId, 0);
      if (withPdm) pdm = maps.pdmMass(j.record.pdmId);
      built = problems::problemOnMap(ground, dem, std::move(pdm), maps.header(j.record.mapId).body);
      built.rovers = rovers;
      built.keepOut = keepOut;
      j.geo = dem->z.geo;
      j.mapGrid = dem->geometry();
    }
    built.threads = j.problem.threads;
    j.problem = std::move(built);
  };
  job.build(job);
  try {
    planner.validate(job.problem, job.params);
    job.eventGrid = planner.eventGrid(job.problem, job.params);
  } catch (const Error& e) {
    const bool ownField = e.field().rfind("rovers", 0) == 0 || e.field() == "map" || e.field() == "pdm";
    rethrowQualified(e, ownField ? "" : "params.");
  }
  job.record.spec = std::move(request.spec);
  job.record.spec["dem_sha256"] = digest;
  job.record.spec["used"] = used;
  job.problem.world = {};
  job.problem.dem.reset();
  job.problem.pdm.reset();
  return job;
}

store::MissionRecord submitMission(ApiContext& ctx, const json& body, const std::string& by) {
  missions::MissionJob job = buildMission(ctx, body);
  job.record.id = store::DataDir::newId();
  job.record.createdAt = store::nowIso();
  const std::string id = job.record.id;
  ctx.missions.submit(std::move(job));
  auto m = *ctx.db.getMission(id);
  publishEvent(ctx, "created", "mission", m.id, m.mapId, m.version, by);
  return m;
}

}  // namespace rover::api
