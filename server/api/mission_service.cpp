#include "server/api/mission_service.hpp"

#include "core/common/error.hpp"
#include "server/api/mission_file.hpp"
#include "server/api/route_kit.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/zones_json.hpp"
#include "server/problems/problem_builder.hpp"
#include "server/store/disk_budget.hpp"

namespace rover::api {


namespace {

// A core Error of the request with its field qualified for the API's error mapping
// ("params.targets"); one that names no field is the body's.
[[noreturn]] void rethrowQualified(const Error& e, const std::string& prefix) {
  throw Error(e.code(), e.field().empty() ? "body" : prefix + e.field(), e.what());
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
  if (!job.record.pdmId.empty()) {
    auto p = ctx.db.getPdm(job.record.pdmId);
    if (!p || p->mapId != job.record.mapId)
      throw ApiError(400, "not_found", "no PDM '" + rj::shown(job.record.pdmId) + "' on this map", "pdm");
  }
  // What the planner plans on, as its description says (PlannerSpecs::ground). Its memory is
  // estimated by the planner and checked against the mission budget first.
  const GridGeometry mapGeometry = ctx.maps.get(job.record.mapId)->dem.geometry();
  rj::checkZonesOnMap(job.problem.keepOut, mapGeometry, "keep_out");
  const int roverCount = static_cast<int>(job.problem.rovers.size());
  MapGround ground;
  try {
    ground = planner.groundOnMap(mapGeometry, job.params);
    job.memory = planner.memoryEstimate(mapGeometry, ground, roverCount, !job.record.pdmId.empty(), job.params);
  } catch (const Error& e) {
    rethrowQualified(e, "params.");
  }
  ctx.missions.admit(job.memory);
  job.build = [&maps = ctx.maps, ground](missions::MissionJob& j) {
    auto dem = maps.demAtCell(j.record.mapId, 0);
    const terrain::Body body = maps.get(j.record.mapId)->body;
    std::shared_ptr<const Raster<float>> pdm;
    if (ground.kind == Ground::DemAndPdm && !j.record.pdmId.empty()) pdm = maps.pdmMass(j.record.pdmId);
    PlanningProblem built = problems::problemOnMap(ground, dem, std::move(pdm), body);
    built.rovers = std::move(j.problem.rovers);  // the request's, kept
    built.keepOut = std::move(j.problem.keepOut);
    built.threads = j.problem.threads;
    j.problem = std::move(built);
    j.geo = dem->z.geo;
    j.mapGrid = dem->geometry();
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
  job.problem.world = {};
  job.problem.dem.reset();
  job.problem.pdm.reset();
  return job;
}

store::MissionRecord submitMission(ApiContext& ctx, const json& body) {
  missions::MissionJob job = buildMission(ctx, body);
  job.record.id = store::DataDir::newId();
  job.record.createdAt = store::nowIso();
  const std::string id = job.record.id;
  ctx.missions.submit(std::move(job));
  return *ctx.db.getMission(id);
}

}  // namespace rover::api
