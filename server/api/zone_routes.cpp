#include "server/api/zone_routes.hpp"

// A map's keep-out zones, versioned (issue 26): the set has a version (each save +1, 0 = never
// saved) and each zone its id ("z1", "z2", ... never reused on a map) and own version. Writes name
// the version they read (preconditions.hpp); the whole set can still be replaced at once, checked
// against the set's version, or one zone added, changed or deleted, checked against that zone's
// version only, so two operators editing different zones never conflict.

#include <set>

#include "maps/georef.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/api/versioned_writes.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/zones_json.hpp"

namespace rover::api {

namespace {

constexpr std::size_t kMaxZoneIdBytes = 24;

const rj::JsonLimits kZoneLimits{rj::kMaxZonesFileBytes, 64};

// "z<N>" (appended, not `"z" + ...`: GCC 12 warns on that, -Wrestrict).
std::string zoneIdOf(long long n) {
  std::string id = "z";
  id += std::to_string(n);
  return id;
}

// Features without an id get the next ones, without a version 1 (zones saved before versions).
void normalise(store::ZoneSet& s) {
  if (!s.body.is_object() || !s.body.contains("features")) s.body = rj::zonesToJson({});
  for (json& f : s.body["features"]) {
    if (!f.contains("id") || !f["id"].is_string()) f["id"] = zoneIdOf(s.nextZone++);
    if (!f.contains("properties") || !f["properties"].is_object()) f["properties"] = json::object();
    if (!f["properties"].contains("version")) f["properties"]["version"] = 1;
  }
}

store::ZoneSet currentSet(ApiContext& ctx, const std::string& mapId) {
  auto s = ctx.db.getZoneSet(mapId);
  store::ZoneSet out = s ? std::move(*s) : store::ZoneSet{rj::zonesToJson({}), 0, 1};
  normalise(out);
  return out;
}

json setJson(const store::ZoneSet& s) {
  json j = s.body;
  j["version"] = s.version;
  return j;
}

json* findZone(store::ZoneSet& s, const std::string& zoneId) {
  for (json& f : s.body["features"])
    if (f["id"] == zoneId) return &f;
  return nullptr;
}

long long zoneVersion(const json& f) { return f["properties"].value("version", 1LL); }

json zoneJson(const json& f, long long setVersion) {
  json j = f;
  j["version"] = zoneVersion(f);
  j["zones_version"] = setVersion;
  return j;
}

// How positions are read: the local frame (default) or ?crs=map (the map's own CRS).
std::function<Eigen::Vector2d(const Eigen::Vector2d&)> toLocalOf(const Request& req, const MapData& map) {
  std::string crs = "local";
  if (auto it = req.query.find("crs"); it != req.query.end()) crs = it->second;
  if (crs != "local" && crs != "map")
    throw ApiError(400, "invalid_parameter", "crs must be local (the default) or map", "crs");
  if (crs == "local") return {};
  const GridGeometry& g = map.dem.geometry();
  const GeoReference& geo = map.dem.z.geo;
  if (!geo.valid) throw ApiError(400, "invalid_parameter", "this map has no CRS: send local metres", "crs");
  return [&g, &geo](const Eigen::Vector2d& xy) { return maps::crsToLocal(g, geo, xy); };
}

// One zone (a GeoJSON Feature with a Polygon) as stored: local frame, on the map; errors name
// "zone..." fields.
json storedZone(const json& feature, const MapData& map, const Request& req) {
  const json wrapped{{"type", "FeatureCollection"}, {"features", json::array({feature})}};
  try {
    if (!feature.is_object() || feature.value("type", json()) != "Feature")
      throw ApiError(400, "invalid_zones", "zone: must be a GeoJSON Feature with a Polygon geometry", "zone");
    const KeepOut k = rj::zonesFromJson(wrapped, "zone", &map.dem.geometry(), toLocalOf(req, map));
    return rj::zonesToJson(k, rj::zoneNames(wrapped))["features"][0];
  } catch (const ApiError& e) {
    auto strip = [](std::string s) {
      const std::string from = "zone.features[0]";
      for (std::size_t at; (at = s.find(from)) != std::string::npos;) s.replace(at, from.size(), "zone");
      return s;
    };
    throw ApiError(e.status(), e.code(), strip(e.what()), strip(e.field()));
  }
}

// The set's limits (zones, vertices in all) over the new set.
void checkSet(const store::ZoneSet& s, const MapData& map) {
  rj::zonesFromJson(s.body, "zones", &map.dem.geometry());
}

void save(ApiContext& ctx, const std::string& mapId, store::ZoneSet& s, long long expected, const Request& req) {
  switch (ctx.db.putZoneSet(mapId, s, expected, req.operatorName)) {
    case store::Cas::Done: s.version = expected + 1; return;
    case store::Cas::Missing: throw mapNotFound(mapId, "id");
    case store::Cas::Stale: {
      // Another server process on the same data dir; this one writes under versionedWrites.
      const store::ZoneSet now = currentSet(ctx, mapId);
      throw versionConflict("the zones of this map", expected, now.version, setJson(now));
    }
  }
}

Response getZones(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  mapOr404(ctx, id, "id");
  const store::ZoneSet s = currentSet(ctx, id);
  return withETag(Response::json(200, setJson(s)), s.version);
}

Response putZones(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  auto map = ctx.maps.get(id);  // 404 for an unknown map
  json body = jsonBody(req, kZoneLimits);
  const auto named = namedVersion(req, &body);
  if (body.contains("crs") && queryString(req, "crs") != "map")
    // A "crs" member (RFC 7946 dropped it; our exports write it) says the file is in a CRS: the
    // caller must say that it is the map's, as we do not reproject between CRSs.
    throw ApiError(400, "invalid_field",
                   "the body names a CRS (a \"crs\" member): send ?crs=map to import coordinates "
                   "in the map's own CRS, or drop it for local metres",
                   "zones.crs");
  const KeepOut zones = rj::zonesFromJson(body, "zones", &map->dem.geometry(), toLocalOf(req, *map));
  json stored = rj::zonesToJson(zones, rj::zoneNames(body));
  // A string id this set holds keeps its zone's identity (and version when unchanged); any other
  // feature (no id, a number id as GeoJSON files may have, an unknown id) is a new zone.
  // One id names one zone: a repeated id would store a zone no /zones/{zone} route can reach.
  std::set<std::string> ids;
  for (std::size_t i = 0; i < body["features"].size(); ++i) {
    const json& f = body["features"][i];
    if (f.contains("id") && f["id"].is_string() && f["id"].get<std::string>().size() <= kMaxZoneIdBytes) {
      if (!ids.insert(f["id"].get<std::string>()).second)
        throw ApiError(400, "invalid_field", "zone id '" + f["id"].get<std::string>() + "' is given twice",
                       "zones.features[" + std::to_string(i) + "].id");
      stored["features"][i]["id"] = f["id"];
    }
  }
  return saveZoneSet(ctx, req, id, std::move(stored), named, false);
}

Response getZone(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  mapOr404(ctx, id, "id");
  store::ZoneSet s = currentSet(ctx, id);
  const json* f = findZone(s, req.params.at("zone"));
  if (!f) throw ApiError(404, "not_found", "no zone '" + rj::shown(req.params.at("zone")) + "' on this map", "zone");
  return withETag(Response::json(200, zoneJson(*f, s.version)), zoneVersion(*f));
}

Response addZone(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  auto map = ctx.maps.get(id);
  const json body = jsonBody(req, kZoneLimits);
  json zone = storedZone(body, *map, req);
  std::lock_guard lock(ctx.versionedWrites);
  store::ZoneSet s = currentSet(ctx, id);
  const long long expected = s.version;  // adding overwrites nothing: no version is asked for
  zone["id"] = zoneIdOf(s.nextZone++);
  zone["properties"]["version"] = 1;
  s.body["features"].push_back(zone);
  checkSet(s, *map);
  save(ctx, id, s, expected, req);
  publishEvent(ctx, "created", "zone", zone["id"], id, 1, req.operatorName);
  Response r = withETag(Response::json(201, zoneJson(zone, s.version)), 1);
  r.headers.emplace_back("Location", "/api/maps/" + id + "/zones/" + zone["id"].get<std::string>());
  return r;
}

// The zone named by the path, its version checked against the one the request names.
json& zoneToWrite(store::ZoneSet& s, const Request& req, const char* what) {
  const std::string& zoneId = req.params.at("zone");
  json* f = findZone(s, zoneId);
  if (!f) throw ApiError(404, "not_found", "no zone '" + rj::shown(zoneId) + "' on this map", "zone");
  const long long named = requiredVersion(req, nullptr, std::string("zone ") + rj::shown(zoneId));
  if (named != zoneVersion(*f))
    throw versionConflict(std::string("zone ") + rj::shown(zoneId) + " (" + what + ")", named, zoneVersion(*f),
                          zoneJson(*f, s.version));
  return *f;
}

Response changeZone(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  auto map = ctx.maps.get(id);
  const json body = jsonBody(req, kZoneLimits);
  (void)namedVersion(req, &body);  // a malformed version is refused before anything else
  json zone = storedZone(body, *map, req);
  std::lock_guard lock(ctx.versionedWrites);
  store::ZoneSet s = currentSet(ctx, id);
  const long long expected = s.version;
  json& f = zoneToWrite(s, req, "changed");
  // The version may come in the body, as in every write.
  zone["id"] = f["id"];
  zone["properties"]["version"] = zoneVersion(f) + 1;
  f = zone;
  checkSet(s, *map);
  save(ctx, id, s, expected, req);
  publishEvent(ctx, "changed", "zone", zone["id"], id, zoneVersion(zone), req.operatorName);
  return withETag(Response::json(200, zoneJson(zone, s.version)), zoneVersion(zone));
}

Response deleteZone(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  mapOr404(ctx, id, "id");
  std::lock_guard lock(ctx.versionedWrites);
  store::ZoneSet s = currentSet(ctx, id);
  const long long expected = s.version;
  const json& f = zoneToWrite(s, req, "deleted");
  const std::string zoneId = f["id"];
  auto& features = s.body["features"];
  for (std::size_t i = 0; i < features.size(); ++i)
    if (features[i]["id"] == zoneId) {
      features.erase(i);
      break;
    }
  save(ctx, id, s, expected, req);
  publishEvent(ctx, "deleted", "zone", zoneId, id, 0, req.operatorName);
  return withETag(Response::json(200, {{"deleted", zoneId}, {"zones_version", s.version}}), s.version);
}

}  // namespace

Response saveZoneSet(ApiContext& ctx, const Request& req, const std::string& id, json stored,
                     std::optional<long long> named, bool restoring) {
  std::lock_guard lock(ctx.versionedWrites);
  store::ZoneSet s = currentSet(ctx, id);
  if (!named && s.version > 0) (void)requiredVersion(req, nullptr, "the zones of this map");
  const long long expected = named.value_or(0);
  if (expected != s.version) throw versionConflict("the zones of this map", expected, s.version, setJson(s));
  for (json& f : stored["features"]) {
    const json* old = f.contains("id") ? findZone(s, f["id"].get<std::string>()) : nullptr;
    if (old) {
      const bool same = (*old)["geometry"] == f["geometry"] &&
                        (*old)["properties"].value("name", "") == f["properties"].value("name", "");
      f["properties"]["version"] = zoneVersion(*old) + (same ? 0 : 1);
    } else if (restoring && f.contains("id") && f["properties"].contains("version")) {
      // A zone deleted since: back with its id (ids are never handed out twice), one version on.
      f["properties"]["version"] = f["properties"]["version"].get<long long>() + 1;
    } else {
      f["id"] = zoneIdOf(s.nextZone++);
      f["properties"]["version"] = 1;
    }
  }
  s.body = std::move(stored);
  save(ctx, id, s, expected, req);
  publishEvent(ctx, "changed", "zones", id, id, s.version, req.operatorName);
  return withETag(Response::json(200, setJson(s)), s.version);
}

namespace {

const json kCrsQuery = {{"type", "string"}, {"enum", {"local", "map"}}};
const char* kCrsDoc = "local (default): metres from the map's lower-left corner; map: the map's own CRS.";

}  // namespace

void addZoneRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/maps/{id}/zones", handler(ctx, getZones),
             routeDoc("A map's keep-out zones: a GeoJSON FeatureCollection of Polygons in the local frame (metres "
                      "from the map's lower-left corner), each Feature with its id and properties.version, and the "
                      "set's `version` (0 and no features when none were saved; also the ETag \"v<N>\").",
                      Operation().returns(200, "The zones.", ref("Zones")).etag().errors({404})));
  router.add("PUT", "/api/maps/{id}/zones", handler(ctx, putZones),
             routeDoc("Replace a map's keep-out zones: a GeoJSON FeatureCollection of Polygons (at most 64 zones, "
                      "1024 vertices in all; rings closed, 3+ distinct points; on or near the map). Names the set's "
                      "version it read (If-Match \"v<N>\" or a top-level \"version\"): 412 with the current set when "
                      "stale, 428 when the map has saved zones and none is named (a first save needs none). Features "
                      "keep their id when it is one of the set's, others get new ones. Local frame by default; "
                      "?crs=map converts from the map's own CRS (as result.geojson exports are written). Answers the "
                      "zones as stored, in the local frame.",
                      Operation()
                          .query("crs", kCrsQuery, kCrsDoc)
                          .ifMatch()
                          .body(ref("Zones"))
                          .returns(200, "The zones as stored, in the local frame.", ref("Zones")).etag()
                          .errors({400, 404, 412, 413, 415, 428, 503, 507}),
                      onPool));
  router.add("POST", "/api/maps/{id}/zones", handler(ctx, addZone),
             routeDoc("Add one keep-out zone (a GeoJSON Feature with a Polygon; the set's limits apply): answers it "
                      "with its new id, its version (1) and the set's version (zones_version). Needs no version: "
                      "adding never overwrites.",
                      Operation()
                          .query("crs", kCrsQuery, kCrsDoc)
                          .body(ref("Zone"))
                          .returns(201, "The zone as stored.", ref("Zone")).etag()
                          .errors({400, 404, 413, 415, 503, 507}),
                      onPool));
  router.add("GET", "/api/maps/{id}/zones/{zone}", handler(ctx, getZone),
             routeDoc("One keep-out zone, with its version (also the ETag).",
                      Operation().returns(200, "The zone.", ref("Zone")).etag().errors({404})));
  router.add("PUT", "/api/maps/{id}/zones/{zone}", handler(ctx, changeZone),
             routeDoc("Change one keep-out zone (a GeoJSON Feature with a Polygon): If-Match names the zone's own "
                      "version (other zones may have changed meanwhile); 412 with the current zone when stale, 428 "
                      "without one.",
                      Operation()
                          .query("crs", kCrsQuery, kCrsDoc)
                          .ifMatch()
                          .body(ref("Zone"))
                          .returns(200, "The zone as stored.", ref("Zone")).etag()
                          .errors({400, 404, 412, 413, 415, 428, 503, 507}),
                      onPool));
  router.add("DELETE", "/api/maps/{id}/zones/{zone}", handler(ctx, deleteZone),
             routeDoc("Delete one keep-out zone: If-Match names its version; 412 with the current zone when stale, "
                      "428 without one.",
                      Operation()
                          .ifMatch()
                          .returns(200, "Deleted; zones_version is the set's new version.", ref("ZoneDeleted"))
                          .errors({400, 404, 412, 428})));
}

}  // namespace rover::api
