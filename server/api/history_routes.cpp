// The saved versions of PDMs and zone sets (issue 26): listed with who saved them and when, one
// read whole, and one restored as the newest version (its own If-Match: the version it replaces).
// The last store::kHistoryPerObject (50) versions of each are kept; they go with their object.
#include "server/api/openapi_kit.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/api/versioned_writes.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"

namespace rover::api {

namespace {

store::PdmRecord pdmOf(ApiContext& ctx, const Request& req) {
  auto p = ctx.db.getPdm(req.params.at("pdm"));
  if (!p || p->mapId != req.params.at("id"))
    throw ApiError(404, "not_found", "no PDM '" + rj::shown(req.params.at("pdm")) + "' on this map", "pdm");
  return std::move(*p);
}

json listing(const std::vector<store::HistoryEntry>& entries) {
  json out = json::array();
  for (const auto& e : entries) out.push_back({{"version", e.version}, {"by", e.by}, {"at", e.at}});
  return out;
}

// A version number from the path: 1 to 16 digits, else 404 (it names no version).
long long versionParam(const std::string& s) {
  if (s.empty() || s.size() > 16 || s.find_first_not_of("0123456789") != std::string::npos)
    throw ApiError(404, "not_found", "a version is a number (see .../history)", "version");
  return std::stoll(s);
}

store::HistoryEntry entryOr404(ApiContext& ctx, const std::string& kind, const std::string& id, long long version) {
  auto e = ctx.db.historyVersion(kind, id, version);
  if (!e)
    throw ApiError(404, "not_found",
                   "no saved version " + std::to_string(version) + " (the last " +
                       std::to_string(store::kHistoryPerObject) + " are kept: see .../history)",
                   "version");
  return std::move(*e);
}

json entryJson(const store::HistoryEntry& e) {
  return {{"version", e.version}, {"by", e.by}, {"at", e.at}, {"body", e.body}};
}

// The version to restore: {"version": N} in the body ("restore": the history's number), and the
// current one in If-Match (required: a restore replaces the current version).
long long restoreWhich(const json& body) {
  if (!body.is_object() || !body.contains("restore"))
    throw ApiError(400, "invalid_field", "name the saved version to restore: {\"restore\": N}", "restore");
  const json& r = body["restore"];
  if (!r.is_number_integer() || r.get<long long>() < 1)
    throw ApiError(400, "invalid_field", "restore must be a saved version number (see .../history)", "restore");
  return r.get<long long>();
}

Response pdmHistory(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOf(ctx, req);
  return Response::json(200, listing(ctx.db.history("pdm", p.id)));
}

Response pdmVersion(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOf(ctx, req);
  return Response::json(200, entryJson(entryOr404(ctx, "pdm", p.id, versionParam(req.params.at("version")))));
}

Response restorePdm(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOf(ctx, req);
  json body = jsonBody(req, rj::kPdmJsonLimits);
  const long long which = restoreWhich(body);
  const long long expected = requiredVersion(req, &body, pdmWhat(p));
  if (expected != p.version) throw versionConflict(pdmWhat(p), expected, p.version, pdmJson(p));
  const store::HistoryEntry e = entryOr404(ctx, "pdm", p.id, which);
  const json& meta = e.body.value("meta", json::object());
  std::optional<std::vector<pdm::Gaussian>> comps;
  if (meta.contains("components") && p.meta.value("kind", "") != "raster")
    comps = rj::gaussiansFromJson({{"components", meta["components"]}});
  return savePdm(ctx, req, p, e.body.value("name", p.name), comps, expected);
}

Response zonesHistory(ApiContext& ctx, const Request& req) {
  mapOr404(ctx, req.params.at("id"), "id");
  return Response::json(200, listing(ctx.db.history("zones", req.params.at("id"))));
}

Response zonesVersion(ApiContext& ctx, const Request& req) {
  mapOr404(ctx, req.params.at("id"), "id");
  return Response::json(200, entryJson(entryOr404(ctx, "zones", req.params.at("id"), versionParam(req.params.at("version")))));
}

Response restoreZones(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  mapOr404(ctx, id, "id");
  json body = jsonBody(req, rj::kPdmJsonLimits);
  const long long which = restoreWhich(body);
  const auto named = namedVersion(req, &body);
  if (!named) (void)requiredVersion(req, &body, "the zones of this map");
  const store::HistoryEntry e = entryOr404(ctx, "zones", id, which);
  json stored = e.body;
  stored.erase("version");
  return saveZoneSet(ctx, req, id, std::move(stored), named, true);
}

http::RouteOptions restoreDoc(const std::string& what) {
  return routeDoc("Restore a saved version of " + what + " as its newest: {\"restore\": N} (a version of .../history), "
                  "If-Match (or \"version\") naming the current version: 412 with the current one when stale, 428 "
                  "without.",
                  Operation()
                      .ifMatch()
                      .body(openapi::kit::object({{"restore", {{"type", "integer"}, {"minimum", 1}}},
                                    {"version", {{"type", "integer"}, {"minimum", 0}}}},
                                   {"restore"}))
                      .returns(200, "The object as stored now (one version on).", {{"type", "object"}})
                      .etag()
                      .errors({400, 404, 412, 413, 415, 428, 503}),
                  onPool);
}

}  // namespace

void addHistoryRoutes(http::Router& router, ApiContext& ctx) {
  const std::string kept = " The last " + std::to_string(store::kHistoryPerObject) + " versions are kept, newest first.";
  router.add("GET", "/api/maps/{id}/pdms/{pdm}/history", handler(ctx, pdmHistory),
             routeDoc("A PDM's saved versions: version, by (the operator), at." + kept,
                      Operation().returns(200, "The versions.", ref("History")).errors({404})));
  router.add("GET", "/api/maps/{id}/pdms/{pdm}/history/{version}", handler(ctx, pdmVersion),
             routeDoc("One saved version of a PDM: its name and meta (kind, components) in body.",
                      Operation().returns(200, "The version.", ref("HistoryEntry")).errors({404})));
  router.add("POST", "/api/maps/{id}/pdms/{pdm}/restore", handler(ctx, restorePdm), restoreDoc("a PDM"));
  router.add("GET", "/api/maps/{id}/zones/history", handler(ctx, zonesHistory),
             routeDoc("A map's saved zone sets: version, by (the operator), at." + kept,
                      Operation().returns(200, "The versions.", ref("History")).errors({404})));
  router.add("GET", "/api/maps/{id}/zones/history/{version}", handler(ctx, zonesVersion),
             routeDoc("One saved zone set (body: the FeatureCollection as saved).",
                      Operation().returns(200, "The version.", ref("HistoryEntry")).errors({404})));
  router.add("POST", "/api/maps/{id}/zones/restore", handler(ctx, restoreZones), restoreDoc("a map's zone set"));
}

}  // namespace rover::api
