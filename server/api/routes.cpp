#include "server/api/routes.hpp"

#include <iostream>

#include "core/common/error.hpp"
#include "server/api/zone_routes.hpp"

namespace rover::api {

using http::ApiError;
using http::Request;
using http::Response;
using nlohmann::json;
using openapi::Operation;
using openapi::ref;

namespace {

// An ApiError for a core validation error; `prefix` qualifies the field (e.g. "params."), and an
// error that names no field is attributed to `fallback` (every error names its field).
ApiError fromCore(const Error& e, const std::string& prefix = "", const std::string& fallback = "body") {
  std::string field = e.field().empty() ? fallback : prefix + e.field();
  return ApiError(400, errorCodeName(e.code()), e.what(), field);
}

// Every handler runs inside this: expected failures leave as ApiError; a core Error is bad input
// (400 with its field); a JSON type error is a body of the wrong shape; anything else is a 500
// whose message shows no server paths (the detail goes to the server's log).
http::Handler guarded(http::Handler handler) {
  return [handler = std::move(handler)](const Request& req) -> Response {
    try {
      return handler(req);
    } catch (const ApiError&) {
      throw;
    } catch (const Error& e) {
      throw fromCore(e);
    } catch (const nlohmann::json::exception&) {
      throw ApiError(400, "bad_json", "the request body has a value of the wrong type", "body");
    } catch (const std::exception& e) {
      std::cerr << "roverplan: " << req.method << " " << req.path << ": internal error: " << e.what() << "\n";
      throw ApiError(500, "internal", "internal error (details are in the server log)", "");
    }
  };
}

}  // namespace

http::Handler guardedRoute(http::Handler handler) { return guarded(std::move(handler)); }

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
}

}  // namespace rover::api
