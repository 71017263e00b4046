// /api/maps/{id}/pdms: a map's PDMs (Gaussian components as JSON, G random ones, or a raster of
// weights): list, create, one PDM, delete.
#include <filesystem>
#include <fstream>
#include <optional>

#include "core/common/error.hpp"
#include "core/pdm/pdm.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/api/versioned_writes.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"
#include "server/store/disk_budget.hpp"

namespace rover::api {

namespace fs = std::filesystem;

namespace {

store::PdmRecord pdmOr404(ApiContext& ctx, const Request& req) {
  auto p = ctx.db.getPdm(req.params.at("pdm"));
  if (!p || p->mapId != req.params.at("id"))
    throw ApiError(404, "not_found", "no PDM '" + rj::shown(req.params.at("pdm")) + "' on this map", "pdm");
  return std::move(*p);
}

Response listPdms(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  mapOr404(ctx, id, "id");
  const Page page = pageOf(req);
  json out = json::array();
  for (const auto& p : ctx.db.listPdms(id, page.limit, page.offset)) out.push_back(pdmJson(p));
  return pageResponse(req, page, std::move(out), ctx.db.countPdms(id));
}

// 201 with the new PDM, told to the event stream.
Response created(ApiContext& ctx, const Request& req, const store::PdmRecord& p) {
  publishEvent(ctx, "created", "pdm", p.id, p.mapId, p.version, req.operatorName);
  return withETag(Response::json(201, pdmJson(p)), p.version);
}

// A PDM document {name, components} or {name, random: G, seed: S} (the body is at most
// kPdmJsonLimits: 413 past it).
Response createPdmFromJson(ApiContext& ctx, const Request& req, const std::string& mapId) {
  const auto& limits = rj::kPdmJsonLimits;
  if (req.bodySize > limits.maxBytes)
    throw ApiError(413, "payload_too_large", "PDM JSON over " + std::to_string(limits.maxBytes >> 10) + " KiB", "body");
  std::string text(static_cast<std::size_t>(req.bodySize), '\0');
  std::ifstream in(req.bodyFile, std::ios::binary);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  json j = rj::parseJsonLimited(text, limits);
  std::string name;
  if (auto it = j.find("name"); it != j.end() && !it->is_null()) {
    if (!it->is_string()) throw ApiError(400, "invalid_field", "name must be a string", "name");
    name = it->get<std::string>();
    rj::checkName(name, "name");
  }
  std::vector<pdm::Gaussian> comps;
  json meta;
  if (j.contains("random")) {
    if (!j["random"].is_number_integer() || j["random"].get<std::int64_t>() < 1 || j["random"].get<std::int64_t>() > 100)
      throw ApiError(400, "invalid_field", "random must be an integer in [1, 100]", "random");
    if (j.contains("seed") && !j["seed"].is_number_unsigned())
      throw ApiError(400, "invalid_field", "seed must be a non-negative integer", "seed");
    auto map = ctx.maps.get(mapId);
    comps = pdm::randomGaussians(map->dem.geometry(), j["random"].get<int>(), j.value("seed", std::uint64_t{1}));
    meta = {{"kind", "random"}, {"seed", j.value("seed", std::uint64_t{1})}};
  } else {
    try {
      comps = rj::gaussiansFromJson(j);
    } catch (const Error& e) {  // an error that names no field is the components'
      throw Error(e.code(), e.field().empty() ? "components" : e.field(), e.what());
    }
    meta = {{"kind", "gaussians"}};
  }
  meta["components"] = rj::toJson(comps)["components"];
  return created(ctx, req, ctx.maps.createPdm(mapId, name, comps, meta, req.operatorName));
}

// A raster body (any GDAL format) of weights, named by ?name=.
Response createPdmFromRaster(ApiContext& ctx, const Request& req, const std::string& mapId) {
  const std::string name = queryString(req, "name");
  rj::checkName(name, "name");
  const std::string moved = (fs::path(ctx.dir.tmpDir()) /
                             (store::DataDir::newId() + fs::path(queryString(req, "filename")).extension().string()))
                                .string();
  fs::rename(req.bodyFile, moved);
  try {
    auto rec = ctx.maps.createPdmFromRaster(mapId, name, moved, req.operatorName);
    store::DataDir::removeTree(moved);
    return created(ctx, req, rec);
  } catch (...) {
    store::DataDir::removeTree(moved);
    throw;
  }
}

Response createPdm(ApiContext& ctx, const Request& req) {
  const std::string mapId = req.params.at("id");
  ctx.maps.get(mapId);  // 404 for an unknown map
  ctx.dir.budget().requireRoom(store::DiskUse::Pdm, mapId, "body");  // 507 before any work
  InvalidateMapAfter after{ctx, mapId};
  if (req.bodyFile.empty() || req.bodySize == 0) throw ApiError(400, "invalid_input", "the request has no body", "body");
  return sendsJson(req) ? createPdmFromJson(ctx, req, mapId) : createPdmFromRaster(ctx, req, mapId);
}

Response getPdm(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOr404(ctx, req);
  return withETag(Response::json(200, pdmJson(p)), p.version);
}

}  // namespace

std::string pdmWhat(const store::PdmRecord& p) { return "PDM '" + rj::shown(p.id) + "'"; }

// A PDM's new name and/or components (Gaussian PDMs), or an older version restored
// (history_routes.cpp): version-checked, one version more, told to the stream.
Response savePdm(ApiContext& ctx, const Request& req, const store::PdmRecord& p, const std::string& name,
                 const std::optional<std::vector<pdm::Gaussian>>& comps, long long expected) {
  InvalidateMapAfter after{ctx, p.mapId};
  std::lock_guard lock(ctx.versionedWrites);
  store::PdmRecord out;
  switch (ctx.maps.changePdm(p, name, comps, expected, req.operatorName, out)) {
    case store::Cas::Done: break;
    case store::Cas::Missing:
      throw ApiError(404, "not_found", "no PDM '" + rj::shown(p.id) + "' on this map", "pdm");
    case store::Cas::Stale: {
      auto now = ctx.db.getPdm(p.id);
      if (!now) throw ApiError(404, "not_found", "no PDM '" + rj::shown(p.id) + "' on this map", "pdm");
      throw versionConflict(pdmWhat(p), expected, now->version, pdmJson(*now));
    }
  }
  publishEvent(ctx, "changed", "pdm", out.id, out.mapId, out.version, req.operatorName);
  return withETag(Response::json(200, pdmJson(out)), out.version);
}

namespace {

Response changePdm(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOr404(ctx, req);
  json body = jsonBody(req, rj::kPdmJsonLimits);
  if (!body.is_object()) throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  for (const auto& item : body.items())
    if (item.key() != "name" && item.key() != "components" && item.key() != "version")
      throw ApiError(400, "unknown_field",
                     "a PDM's name and components can be changed (with its version), not '" + rj::shown(item.key()) + "'",
                     rj::shown(item.key()));
  const long long expected = requiredVersion(req, &body, pdmWhat(p));
  // Checked first: a stale write is answered 412 whatever else it holds.
  if (expected != p.version) throw versionConflict(pdmWhat(p), expected, p.version, pdmJson(p));
  std::string name = p.name;
  if (auto it = body.find("name"); it != body.end() && !it->is_null()) {
    if (!it->is_string()) throw ApiError(400, "invalid_field", "name must be a string", "name");
    name = it->get<std::string>();
    rj::checkName(name, "name");
    if (name.empty()) throw ApiError(400, "invalid_field", "a PDM's name cannot be empty", "name");
  }
  std::optional<std::vector<pdm::Gaussian>> comps;
  if (body.contains("components")) {
    if (p.meta.value("kind", "") == "raster")
      throw ApiError(400, "invalid_field", "a raster PDM's weights cannot be edited: upload a new raster", "components");
    try {
      comps = rj::gaussiansFromJson(body);
    } catch (const Error& e) {
      throw Error(e.code(), e.field().empty() ? "components" : e.field(), e.what());
    }
  }
  return savePdm(ctx, req, p, name, comps, expected);
}

Response deletePdm(ApiContext& ctx, const Request& req) {
  const store::PdmRecord p = pdmOr404(ctx, req);
  // A delete may name the version it saw (then a changed PDM is not deleted); it need not.
  if (auto named = namedVersion(req); named && *named != p.version)
    throw versionConflict(pdmWhat(p), *named, p.version, pdmJson(p));
  InvalidateMapAfter after{ctx, p.mapId};
  ctx.db.deletePdm(p.id);
  ctx.dir.remove(ctx.dir.pdmDir(p.id));
  ctx.maps.forgetPdm(p.mapId, p.id, std::nullopt);  // its tiles, overviews, mass pyramids, cached masses
  publishEvent(ctx, "deleted", "pdm", p.id, p.mapId, 0, req.operatorName);
  return Response::json(200, {{"deleted", p.id}});
}

http::RouteOptions createOptions() {
  http::RouteOptions o;
  o.streamBody = true;
  o.blocking = onPool;
  o.summary = "Create a PDM: JSON {name, components:[{x,y,sigma_x,sigma_y,rotation_deg,weight}]} "
              "or {name, random: G, seed: S}, or a raster body (any GDAL format) of weights.";
  o.openapi = Operation()
                  .query("name", {{"type", "string"}}, "A raster body's PDM name.")
                  .query("filename", {{"type", "string"}}, "A raster body's file name.")
                  .body(ref("PdmRequest"))
                  .body({{"type", "string"}, {"format", "binary"}}, "application/octet-stream")
                  .returns(201, "Created.", ref("Pdm"))
                  .etag()
                  .errors({400, 404, 413, 503, 507})
                  .toJson();
  return o;
}

}  // namespace

void addPdmRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/maps/{id}/pdms", handler(ctx, listPdms),
             routeDoc("List a map's PDMs, oldest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
                      Operation().listing("Pdm").errors({404})));
  router.add("POST", "/api/maps/{id}/pdms", handler(ctx, createPdm), createOptions());
  router.add("GET", "/api/maps/{id}/pdms/{pdm}", handler(ctx, getPdm),
             routeDoc("One PDM, with its version (also the ETag).",
                      Operation().returns(200, "The PDM.", ref("Pdm")).etag().errors({404})));
  router.add("PUT", "/api/maps/{id}/pdms/{pdm}", handler(ctx, changePdm),
             routeDoc("Change a PDM: {name?, components?} (components: Gaussian PDMs only; an edited random PDM "
                      "becomes a Gaussian one), naming the version read (If-Match \"v<N>\" or \"version\"): 412 "
                      "with the current PDM when stale, 428 without one. Every version is kept in its history "
                      "(the last 50). Missions already launched keep the mass they were given.",
                      Operation()
                          .ifMatch()
                          .body(ref("PdmChange"))
                          .returns(200, "The PDM as stored.", ref("Pdm"))
                          .etag()
                          .errors({400, 404, 412, 413, 415, 428, 503, 507}),
                      onPool));
  router.add("DELETE", "/api/maps/{id}/pdms/{pdm}", handler(ctx, deletePdm),
             routeDoc("Delete a PDM (and its history). If-Match is optional: when given and stale, 412 and nothing is "
                      "deleted.",
                      Operation().ifMatch().returns(200, "Deleted.", ref("Deleted")).errors({400, 404, 412})));
}

}  // namespace rover::api
