// /api/maps: list, upload (any raster GDAL reads, imported in the jail), one map, delete.
#include <filesystem>
#include <set>

#include "core/common/error.hpp"
#include "maps/dem_import_options.hpp"
#include "server/api/multipart.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/json/json_edge.hpp"

namespace rover::api {

namespace fs = std::filesystem;

namespace {

// Removes the paths it holds when it goes out of scope, unless released: every error path of
// an upload leaves nothing behind in data/tmp.
struct RemoveOnExit {
  std::vector<std::string> paths;
  ~RemoveOnExit() {
    for (const auto& p : paths) store::DataDir::removeTree(p);
  }
  void release() { paths.clear(); }
};

// Moves the request body (or its multipart file parts) into upload files for import. Plain
// multipart fields are at most 64 KiB each (413 naming the field). On a throw nothing it made
// is left; on success the caller owns the returned files.
std::vector<UploadedFile> uploadedFiles(const Request& req, store::DataDir& dir, std::string& name,
                                        std::map<std::string, std::string>& options) {
  if (req.bodyFile.empty() || req.bodySize == 0)
    throw ApiError(400, "invalid_input", "the request has no body: send the DEM file", "file");
  std::vector<UploadedFile> files;
  RemoveOnExit made;  // the staging folder of the parts, and the files moved out of it
  const std::string boundary = multipartBoundary(req.header("content-type"));
  if (!boundary.empty()) {
    const std::string parts = dir.stagingDir();
    made.paths.push_back(parts);
    std::set<std::string> seen;
    for (const auto& p : splitMultipart(req.bodyFile, boundary, parts)) {
      if (p.filename.empty()) {
        // An option named twice (two fields, or a field and the query) is refused, not guessed.
        auto once = [&](std::string& slot) {
          if (!slot.empty() || seen.count(p.name))
            throw ApiError(400, "invalid_parameter", p.name + " is given more than once (fields and query)", p.name);
          seen.insert(p.name);
          slot = p.value;
        };
        if (p.name == "name") once(name);
        if (auto o = options.find(p.name); o != options.end()) once(o->second);
        continue;
      }
      const std::string moved = (fs::path(dir.tmpDir()) / store::DataDir::newId()).string();
      fs::rename(p.path, moved);
      made.paths.push_back(moved);
      files.push_back({moved, p.filename});
    }
    if (files.empty()) throw ApiError(400, "invalid_input", "the multipart body holds no file part", "file");
    store::DataDir::removeTree(parts);
    made.release();
  } else {
    const std::string moved = (fs::path(dir.tmpDir()) / store::DataDir::newId()).string();
    fs::rename(req.bodyFile, moved);
    std::string filename = queryString(req, "filename");
    files.push_back({moved, filename.empty() ? "upload.tif" : filename});
  }
  return files;
}

Response listMaps(ApiContext& ctx, const Request& req) {
  const Page page = pageOf(req);
  json out = json::array();
  for (const auto& m : ctx.db.listMaps(page.limit, page.offset)) out.push_back(mapJson(m));
  return pageResponse(req, page, std::move(out), ctx.db.countMaps());
}

// The DEM options (maps/dem_import_options: cell, crop, crop_px, vertical_scale, vertical_offset,
// body) as query
// parameters or plain multipart fields, read by the CLI's own parser.
Response uploadMap(ApiContext& ctx, const Request& req) {
  std::string name = queryString(req, "name");
  std::map<std::string, std::string> options;
  for (const auto& info : maps::demImportOptionInfos()) options[info.key] = queryString(req, info.key);
  auto files = uploadedFiles(req, ctx.dir, name, options);
  try {
    rj::checkName(name, "name");
    for (const auto& [key, value] : options)
      if (value.size() > 200) throw ApiError(400, "invalid_parameter", key + " is longer than 200 bytes", key);
    const maps::DemImport import = maps::parseDemImportOptions(options);
    const store::MapRecord m = ctx.maps.importDem(files, name, import);
    publishEvent(ctx, "created", "map", m.id, m.id, 1, req.operatorName);
    return Response::json(201, mapJson(m));
  } catch (...) {
    for (auto& f : files) store::DataDir::removeTree(f.path);
    throw;
  }
}

Response getMap(ApiContext& ctx, const Request& req) {
  const std::string& id = req.params.at("id");
  Response r;
  {
    std::lock_guard lock(ctx.mapCacheMutex);
    if (auto it = ctx.mapBodyCache.find(id); it != ctx.mapBodyCache.end()) {
      r.body = it->second.body;
      return withETag(std::move(r), it->second.version);
    }
  }
  const std::uint64_t ticket = ctx.mapCacheTicket();  // before the reads
  const store::MapRecord m = mapOr404(ctx, id, "id");
  json j = mapJson(m);
  // The first kMaxPage PDMs; pdms_total says when /api/maps/{id}/pdms holds more.
  j["pdms"] = json::array();
  for (const auto& p : ctx.db.listPdms(m.id, kMaxPage, 0)) j["pdms"].push_back(pdmJson(p));
  j["pdms_total"] = ctx.db.countPdms(m.id);
  r = Response::json(200, j);
  ctx.cacheMapBody(id, r.body, m.version, ticket);
  return withETag(std::move(r), m.version);
}

// PATCH /api/maps/{id} {"name", "version"?}: a versioned rename, as PATCH /api/missions/{id}.
Response renameMap(ApiContext& ctx, const Request& req) {
  const std::string id = req.params.at("id");
  json body = jsonBody(req, rj::kMissionJsonLimits);
  const std::string name = newNameOf(body);
  const std::string what = "map " + rj::shown(id);
  mapOr404(ctx, id, "id");
  const long long expected = requiredVersion(req, &body, what);
  std::lock_guard lock(ctx.versionedWrites);
  InvalidateMapAfter after{ctx, id};
  const store::MapRename done = ctx.db.renameMap(id, name, expected);
  switch (done.cas) {
    case store::Cas::Done: break;
    case store::Cas::Missing: throw mapNotFound(id, "id");
    case store::Cas::Stale: {
      const store::MapRecord now = mapOr404(ctx, id, "id");
      throw versionConflict(what, expected, now.version, mapJson(now));
    }
  }
  if (!done.takenBy.empty())
    throw ApiError(409, "name_taken",
                   "map '" + rj::shown(done.takenBy) + "' is already named '" + rj::shown(name) +
                       "': map names are unique, choose another",
                   "name");
  // A DELETE may land between the update and the read back: then it is gone (404).
  const store::MapRecord m = mapOr404(ctx, id, "id");
  publishEvent(ctx, "changed", "map", id, id, m.version, req.operatorName);
  return withETag(Response::json(200, mapJson(m)), m.version);
}

Response deleteMap(ApiContext& ctx, const Request& req) {
  InvalidateMapAfter after{ctx, req.params.at("id")};
  ctx.maps.remove(req.params.at("id"));
  publishEvent(ctx, "deleted", "map", req.params.at("id"), req.params.at("id"), 0, req.operatorName);
  return Response::json(200, {{"deleted", req.params.at("id")}});
}

http::RouteOptions uploadOptions() {
  http::RouteOptions upload;
  upload.streamBody = true;
  upload.blocking = onPool;
  upload.summary = "Upload a DEM (raw body with ?filename=, or multipart/form-data with file parts; "
                   "PDS3 .IMG+.LBL pairs as two parts or a zip), ?name=&cell=&crop=|crop_px=&vertical_scale=&vertical_offset=&body= "
                   "(or plain multipart fields of those names).";
  Operation op;
  op.query("name", {{"type", "string"}}, "The map's name (default: from the file).")
      .query("filename", {{"type", "string"}}, "A raw body's file name (its extension picks the driver).");
  for (const auto& o : maps::demImportOptionInfos())
    op.query(o.key, {{"type", "string"}, {"pattern", o.pattern}}, o.doc);
  op.body(ref("MapUpload"), "multipart/form-data")
      .body({{"type", "string"}, {"format", "binary"}}, "application/octet-stream")
      .returns(201, "Imported.", ref("Map"))
      .errors({400, 413, 503, 507});
  upload.openapi = op.toJson();
  return upload;
}

}  // namespace

void addMapRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/maps", handler(ctx, listMaps),
             routeDoc("List maps, oldest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
                      Operation().listing("Map")));
  router.add("POST", "/api/maps", handler(ctx, uploadMap), uploadOptions());
  router.add("GET", "/api/maps/{id}", handler(ctx, getMap),
             routeDoc("One map: size, cell size, CRS, elevation range, class percentages, its first 500 PDMs "
                      "(pdms_total counts them all).",
                      Operation().returns(200, "The map.", ref("Map")).etag().errors({404})));
  router.add("PATCH", "/api/maps/{id}", handler(ctx, renameMap),
             routeDoc("Rename a map: {\"name\": \"...\"} (at most 200 characters, no control characters, no other "
                      "map's name: 409 name_taken), naming the version read (If-Match \"v<N>\" or \"version\"): "
                      "412 with the current map when stale, 428 without one.",
                      Operation()
                          .ifMatch()
                          .body(ref("MapName"))
                          .returns(200, "Renamed.", ref("Map"))
                          .etag()
                          .errors({400, 404, 409, 412, 415, 428})));
  router.add("DELETE", "/api/maps/{id}", handler(ctx, deleteMap),
             routeDoc("Delete a map and its PDMs (missions keep their records and results).",
                      Operation().returns(200, "Deleted.", ref("Deleted")).errors({404, 503}), onPool));
}

}  // namespace rover::api
