#include "server/api/zone_routes.hpp"

#include "maps/georef.hpp"
#include "server/api/route_kit.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/zones_json.hpp"

namespace rover::api {


void addZoneRoutes(http::Router& router, ApiContext& ctx) {
  http::RouteOptions get;
  get.summary =
      "A map's keep-out zones: a GeoJSON FeatureCollection of Polygons in the local frame (metres "
      "from the map's lower-left corner), empty when none were saved.";
  get.openapi = openapi::Operation().returns(200, "The zones.", openapi::ref("Zones")).errors({404}).toJson();
  router.add("GET", "/api/maps/{id}/zones", [&ctx](const Request& req) {
    const std::string& id = req.params.at("id");
    mapOr404(ctx, id, "id");
    auto zones = ctx.db.getZones(id);
    return Response::json(200, zones ? *zones : rj::zonesToJson({}));
  }, get);

  http::RouteOptions put;
  put.blocking = true;  // may load the map from disk
  put.summary =
      "Replace a map's keep-out zones: a GeoJSON FeatureCollection of Polygons (at most 64 zones, "
      "1024 vertices in all; rings closed, 3+ distinct points; on or near the map). Local frame by "
      "default; ?crs=map converts from the map's own CRS (as result.geojson exports are written). "
      "Answers the zones as stored, in the local frame.";
  put.openapi = openapi::Operation()
                    .query("crs", {{"type", "string"}, {"enum", {"local", "map"}}},
                           "local (default): metres from the map's lower-left corner; map: the map's own CRS.")
                    .body(openapi::ref("Zones"))
                    .returns(200, "The zones as stored, in the local frame.", openapi::ref("Zones"))
                    .errors({400, 404, 413, 415, 503, 507})
                    .toJson();
  router.add("PUT", "/api/maps/{id}/zones", [&ctx](const Request& req) {
    const std::string& id = req.params.at("id");
    auto map = ctx.maps.get(id);  // 404 for an unknown map
    const rj::JsonLimits limits{rj::kMaxZonesFileBytes, 64};
    json body = jsonBody(req, limits);
    std::string crs = "local";
    if (auto it = req.query.find("crs"); it != req.query.end()) crs = it->second;
    if (crs != "local" && crs != "map")
      throw ApiError(400, "invalid_parameter", "crs must be local (the default) or map", "crs");
    // A "crs" member (RFC 7946 dropped it; our exports write it) says the file is in a CRS: the
    // caller must say that it is the map's, as we do not reproject between CRSs.
    if (body.contains("crs") && crs != "map")
      throw ApiError(400, "invalid_field",
                     "the body names a CRS (a \"crs\" member): send ?crs=map to import coordinates "
                     "in the map's own CRS, or drop it for local metres",
                     "zones.crs");
    const GridGeometry& g = map->dem.geometry();
    std::function<Eigen::Vector2d(const Eigen::Vector2d&)> toLocal;
    if (crs == "map") {
      const GeoReference& geo = map->dem.z.geo;
      if (!geo.valid) throw ApiError(400, "invalid_parameter", "this map has no CRS: send local metres", "crs");
      toLocal = [&g, &geo](const Eigen::Vector2d& xy) { return maps::crsToLocal(g, geo, xy); };
    }
    const KeepOut zones = rj::zonesFromJson(body, "zones", &g, toLocal);
    const json stored = rj::zonesToJson(zones, rj::zoneNames(body));
    if (!ctx.db.setZones(id, stored)) throw mapNotFound(id, "id");
    return Response::json(200, stored);
  }, put);
}

}  // namespace rover::api
