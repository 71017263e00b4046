// /api/missions: launch (through the mission service), list, one mission, cancel or delete,
// rename, its files, and its live stream.
#include <filesystem>
#include <map>

#include "server/api/mission_file.hpp"
#include "server/api/mission_map_file.hpp"
#include "server/api/mission_service.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"

namespace rover::api {

namespace fs = std::filesystem;

namespace {

// No media type is registered for MCAP; Foxglove's own tools serve it as bytes.
constexpr const char* kMcapMediaType = "application/octet-stream";

Response launchMission(ApiContext& ctx, const Request& req) {
  return Response::json(202, missionJson(submitMission(ctx, jsonBody(req, rj::kMissionJsonLimits), req.operatorName)));
}

Response listMissions(ApiContext& ctx, const Request& req) {
  const Page page = pageOf(req);
  json out = json::array();
  for (const auto& m : ctx.db.listMissions(page.limit, page.offset)) out.push_back(missionJson(m));
  return pageResponse(req, page, std::move(out), ctx.db.countMissions());
}

Response getMission(ApiContext& ctx, const Request& req) {
  const store::MissionRecord m = missionOr404(ctx, req.params.at("id"));
  // Whether its result files are there: asked before the folder is looked at, as the worker
  // commits the files before it lets the mission go (so "none" is never said of a coming result).
  const bool pending = ctx.missions.resultPending(m.id);
  json j = missionJson(m);
  if (auto s = ctx.missions.stream(m.id)) {
    json live = s->summary();
    j["progress"] = live["progress"];
    j["step"] = live["step"];
  }
  j["result"] = pending || !isFinal(m.status)                                     ? "pending"
                : fs::exists(fs::path(ctx.dir.missionDir(m.id)) / "result.json") ? "ready"
                                                                                  : "none";
  return withETag(Response::json(200, j), m.version);
}

Response cancelOrDeleteMission(ApiContext& ctx, const Request& req) {
  const std::string id = req.params.at("id");
  const store::MissionRecord m = missionOr404(ctx, id);
  switch (ctx.missions.cancel(id)) {
    case missions::MissionManager::CancelOutcome::Cancelled:
      // Its "cancelled" status is an event from the manager (ApiContext wires onStatus).
      return Response::json(202, {{"id", id}, {"status", "cancelling"}});
    case missions::MissionManager::CancelOutcome::Finishing:
      throw ApiError(409, "not_finished",
                     "mission " + rj::shown(id) + " has stopped and is storing its result: try again when it has ended", "id");
    case missions::MissionManager::CancelOutcome::NotActive:
      break;
  }
  // Not running (any more): the run is deleted, its row first so no listing shows a run whose
  // files are half gone. A mission that is still finishing cannot be deleted yet.
  if (!isFinal(m.status))
    throw ApiError(409, "not_finished", "mission " + rj::shown(id) + " is " + std::string(enumName(m.status)) + ": try again when it has ended", "id");
  // Only the request whose delete removed the row says so; a concurrent one finds nothing.
  if (!ctx.db.deleteMission(id)) throw missionNotFound(id);
  ctx.missions.forget(id);
  ctx.dir.remove(ctx.dir.missionDir(id));
  publishEvent(ctx, "deleted", "mission", id, m.mapId, 0, req.operatorName);
  return Response::json(200, {{"deleted", id}});
}

Response renameMission(ApiContext& ctx, const Request& req) {
  const std::string id = req.params.at("id");
  json body = jsonBody(req, rj::kMissionJsonLimits);
  const std::string label = renamedTo(body, "label", true);
  const std::string what = "mission " + rj::shown(id);
  missionOr404(ctx, id);
  const long long expected = requiredVersion(req, &body, what);
  std::lock_guard lock(ctx.versionedWrites);
  switch (ctx.db.relabelMission(id, label, expected)) {
    case store::Cas::Done: break;
    case store::Cas::Missing: throw missionNotFound(id);
    case store::Cas::Stale: {
      const store::MissionRecord now = missionOr404(ctx, id);
      throw versionConflict(what, expected, now.version, missionJson(now));
    }
  }
  // A DELETE may land between the update and the read back: then it is gone (404).
  const store::MissionRecord m = missionOr404(ctx, id);
  publishEvent(ctx, "changed", "mission", id, m.mapId, m.version, req.operatorName);
  return withETag(Response::json(200, missionJson(m)), m.version);
}

// mission.json: recorded at launch; runs launched before that name their map's current grid.
Response missionFileOf(ApiContext& ctx, const store::MissionRecord& m) {
  std::string digest;
  if (m.spec.is_object() && m.spec.contains("dem_sha256") && m.spec["dem_sha256"].is_string())
    digest = m.spec["dem_sha256"].get<std::string>();
  else if (ctx.db.getMap(m.mapId))
    digest = mapDigest(ctx, m.mapId);
  return withAttachment(Response::json(200, missionFile(m, digest, ctx.version)), "mission-" + m.id + ".json");
}

Response getMissionFile(ApiContext& ctx, const Request& req) {
  const std::string id = req.params.at("id"), file = req.params.at("file");
  const store::MissionRecord m = missionOr404(ctx, id);
  if (file == "mission.json") return missionFileOf(ctx, m);
  const std::string attachment = "mission-" + id + "-" + file;
  if (file == "map.png" || file == "map.tif")
    return withAttachment(fileResponse(missionMapFile(ctx, m, file.substr(4)), file == "map.png" ? "image/png" : "image/tiff"),
                          attachment);
  static const std::map<std::string, std::string> types{{"result.json", "application/json"},
                                                        {"result.geojson", "application/geo+json"},
                                                        {"result.csv", "text/csv"},
                                                        {"replay.mcap", kMcapMediaType}};
  auto t = types.find(file);
  if (t == types.end())
    throw ApiError(404, "not_found",
                   "no file '" + rj::shown(file) + "' (mission.json, result.json, result.geojson, result.csv, replay.mcap, map.png, map.tif)",
                   "file");
  // Asked before the folder is looked at: the worker commits the files, then lets the mission go.
  const bool pending = ctx.missions.resultPending(id);
  const fs::path path = fs::path(ctx.dir.missionDir(id)) / file;
  if (!fs::exists(path)) {
    // A cancelled run stores its partial result after its status turned final.
    if (pending && isFinal(m.status))
      throw ApiError(409, "not_ready", "mission " + rj::shown(id) + " is " + std::string(enumName(m.status)) +
                                           ": its result is being stored, try again in a moment", "id");
    // An ended run without files (failed, cancelled before it stored anything) will never
    // have them: say so, with the reason it ended.
    // A result stored before replays were written (issue 28) has every file but this one.
    if (file == "replay.mcap" && fs::exists(fs::path(ctx.dir.missionDir(id)) / "result.json"))
      throw ApiError(409, "no_result",
                     "mission " + rj::shown(id) + " was stored before MCAP replays were recorded: launch its "
                     "mission.json again for one", "id");
    if (isFinal(m.status))
      throw ApiError(409, "no_result",
                     "mission " + rj::shown(id) + " ended " + std::string(enumName(m.status)) + " without a result" +
                         (m.message.empty() ? std::string() : ": " + m.message),
                     "id");
    throw ApiError(409, "not_ready", "mission " + rj::shown(id) + " is " + std::string(enumName(m.status)) + ": no result yet", "id");
  }
  return withAttachment(fileResponse(path.string(), t->second), attachment);
}

}  // namespace

void addMissionRoutes(http::Router& router, ApiContext& ctx) {
  router.add("POST", "/api/missions", handler(ctx, launchMission),
             routeDoc("Launch a mission {map, pdm?, planner, rovers:[{x,y,heading}], params:{...}, pace?}; "
                      "validated fully, then queued (202). A mission file (GET .../mission.json) is accepted as it is.",
                      Operation()
                          .body({{"anyOf", {ref("MissionRequest"), ref("MissionFile")}}})
                          .returns(202, "Queued.", ref("Mission"))
                          .errors({400, 409, 413, 415, 429, 503, 507}),
                      onPool));
  router.add("GET", "/api/missions", handler(ctx, listMissions),
             routeDoc("List missions, newest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
                      Operation().listing("Mission")));
  router.add("GET", "/api/missions/{id}", handler(ctx, getMission),
             routeDoc("One mission: status, progress, metrics, and whether its result files are there (`result`).",
                      Operation().returns(200, "The mission.", ref("Mission")).etag().errors({404})));
  router.add("DELETE", "/api/missions/{id}", handler(ctx, cancelOrDeleteMission),
             routeDoc("Cancel a queued or running mission (202: its status is cancelled at once, the planner stops "
                      "within one step and its partial result is stored after: `result` says when), or delete "
                      "an ended one with its result files (200; 409 not_finished while its result is stored).",
                      Operation()
                          .returns(200, "Deleted (it had ended).", ref("Deleted"))
                          .returns(202, "Cancelling (it was queued or running).", ref("Cancelling"))
                          .errors({404, 409})));
  router.add("PATCH", "/api/missions/{id}", handler(ctx, renameMission),
             routeDoc("Rename a run: {\"label\": \"...\"} (at most 200 characters, no control characters), naming "
                      "the version read (If-Match \"v<N>\" or \"version\"): 412 with the current mission when "
                      "stale, 428 without one.",
                      Operation()
                          .ifMatch()
                          .body(ref("MissionLabel"))
                          .returns(200, "Renamed.", ref("Mission"))
                          .etag()
                          .errors({400, 404, 412, 415, 428})));
  router.add("GET", "/api/missions/{id}/{file}", handler(ctx, getMissionFile),
             routeDoc("A mission's file (mission.json: everything to run it again, POST it to /api/missions), or "
                      "a finished mission's result: result.json, result.geojson (map CRS: tracks, route, targets, "
                      "zones, incidents), result.csv (every sample, both frames), replay.mcap (the replay for "
                      "Foxglove/Lichtblick: per rover foxglove.PoseInFrame, LocationFix when the map has a CRS, and "
                      "telemetry on the mission clock; the terrain as a foxglove.Grid; route, paths, targets and "
                      "zones as a SceneUpdate; incidents as foxglove.Log; JSON encoding, zstd chunks, indexed), "
                      "map.png (the map with its "
                      "legend and scale bar, rovers numbered from 1, at most 4096 px a side), map.tif (the mission's values "
                      "as Float32 bands over the map's extent in its CRS, each with its description, nodata -9999: "
                      "elevation (m), traversability class at the mission's slope thresholds, visits of the final "
                      "coverage or team search grid, and the PDM when the mission had one).",
                      Operation()
                          .returns(200, "mission.json (MissionFile), result.json, result.geojson or result.csv.",
                                   {{"oneOf", {ref("MissionFile"), ref("PlanResult")}}})
                          .returns(200, "result.geojson.", {{"type", "object"}}, "application/geo+json")
                          .returns(200, "result.csv.", {{"type", "string"}}, "text/csv")
                          .returns(200, "replay.mcap (MCAP, https://mcap.dev/spec).", {{"type", "string"}, {"format", "binary"}},
                                   kMcapMediaType)
                          .returns(200, "map.png.", nullptr, "image/png")
                          .returns(200, "map.tif: value bands (GeoTIFF).", nullptr, "image/tiff")
                          .errors({404, 409, 503}),
                      onPool));

  http::RouteOptions ws;
  ws.openapi = Operation().errors({404, 503}).toJson();  // 503: subscriber limits (ws_admission.hpp)
  ws.summary = "WebSocket: a snapshot, then live events (binary grid frames, JSON poses/progress/overlay, "
               "incidents as they are found: {\"type\":\"incidents\",from,complete,incidents}), "
               "then {\"type\":\"done\"}; see README for the protocol.";
  router.addWebSocket("/api/missions/{id}/stream", [&ctx](const Request& req, std::shared_ptr<http::WsConnection> c) {
    auto s = ctx.missions.stream(req.params.at("id"));
    if (!s) throw missionNotFound(req.params.at("id"));
    return s->subscribe(std::move(c));
  }, ws);
}

}  // namespace rover::api
