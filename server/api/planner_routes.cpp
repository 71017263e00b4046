// GET /api/planners: every registered planner as it describes itself (core/planning/planner_specs).
#include "server/api/route_kit.hpp"
#include "server/json/planner_json.hpp"

namespace rover::api {


namespace {

// ?map=ID: the defaults each planner takes from that map (its cell, its body's gravity) filled in.
Response listPlanners(ApiContext& ctx, const Request& req) {
  json mapInfo;
  std::shared_ptr<const MapData> map;
  if (const std::string id = queryString(req, "map"); !id.empty()) {
    mapOr404(ctx, id, "map");
    map = ctx.maps.get(id);
    mapInfo = {{"map", id}, {"body", terrain::bodyName(map->body)}};
  }
  json out = json::array();
  for (const auto& name : ctx.planners.names()) {
    const Planner& p = ctx.planners.get(name);
    out.push_back(rj::plannerJson(p, mapInfo, map ? p.mapDefaults(map->dem.geometry(), map->body) : ParamSet{}));
  }
  return Response::json(200, out);
}

}  // namespace

void addPlannerRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/planners", handler(ctx, listPlanners),
             routeDoc("Registered planners with every parameter, its default, unit and range, and what each "
                      "describes of itself: the ground it plans on, where its rovers start, its progress curve, "
                      "metrics and stages; ?map=ID fills in the defaults that come from the map (coverage_cell, "
                      "gravity) and its body.",
                      openapi::Operation()
                          .query("map", kIdSchema, "A map id: fill in the defaults that come from it.")
                          .returns(200, "Every planner.", {{"type", "array"}, {"items", openapi::ref("Planner")}})
                          .errors({404}),
                      onPool));
}

}  // namespace rover::api
