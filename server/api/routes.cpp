#include "server/api/routes.hpp"

#include "core/common/error.hpp"
#include "server/api/route_kit.hpp"
#include "server/api/zone_routes.hpp"

namespace rover::api {

using http::Request;
using http::Response;
using nlohmann::json;
using openapi::Operation;
using openapi::ref;

http::RouteOptions routeDoc(const std::string& summary, const openapi::Operation& op, bool blocking) {
  http::RouteOptions o;
  o.summary = summary;
  o.blocking = blocking;
  o.openapi = op.toJson();
  return o;
}

// One file per resource (planner_routes, map_routes, layer_routes, zone_routes, pdm_routes,
// mission_routes, study_routes), registered in this order.
void addApiRoutes(http::Router& router, ApiContext& ctx) {
  if (!ctx.events) {
    store::Database& db = ctx.db;
    ctx.events = std::make_shared<streams::EventHub>(static_cast<std::uint64_t>(db.counter("event_seq")),
                                                     [&db](std::uint64_t seq) { db.setCounter("event_seq", static_cast<long long>(seq)); });
  }
  // Mission statuses from the workers go out as events too.
  ctx.missions.onStatus = [&ctx](const std::string& id, RunStatus) {
    try {
      if (auto m = ctx.db.getMission(id)) publishEvent(ctx, "changed", "mission", id, m->mapId, m->version, "");
    } catch (const std::exception&) {
      // An event lost to a failing database: the row is what clients reload.
    }
  };
  // A map's elevation compressed in the background (raw -> cog): its cached body goes, and
  // clients hear that the map changed (its version stays: its content is the same).
  ctx.maps.onStorageChanged = [&ctx](const std::string& id) {
    ctx.invalidateMap(id);
    try {
      if (auto m = ctx.db.getMap(id)) publishEvent(ctx, "changed", "map", id, id, m->version, "");
    } catch (const std::exception&) {
      // An event lost to a failing database: the row is what clients reload.
    }
  };
  http::RouteOptions open;
  open.requireAuth = false;
  open.summary = "Liveness and a few counters (no token needed).";
  open.openapi = Operation().returns(200, "Alive.", ref("Health")).toJson();
  router.add("GET", "/api/health", [&ctx](const Request&) {
    return Response::json(200, {{"status", "ok"},
                                {"version", ctx.version},
                                {"maps", ctx.db.countMaps()},
                                {"missions_running", ctx.missions.running()},
                                {"missions_queued", ctx.missions.queued()},
                                {"planners", ctx.planners.names()}});
  }, open);

  router.add("GET", "/api/openapi.json", [&router, &ctx](const Request&) {
    return Response::json(200, openapi::document(router, ctx.planners, ctx.version));
  }, routeDoc("This document.", Operation().returns(200, "The OpenAPI 3.0.3 document.", {{"type", "object"}})));

  addPlannerRoutes(router, ctx);
  addMapRoutes(router, ctx);
  addLayerRoutes(router, ctx);
  addZoneRoutes(router, ctx);
  addPdmRoutes(router, ctx);
  addMissionRoutes(router, ctx);
  if (ctx.studies) addStudyRoutes(router, ctx);
  addHistoryRoutes(router, ctx);
  addEventRoutes(router, ctx);
}

}  // namespace rover::api
