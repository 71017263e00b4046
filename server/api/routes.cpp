#include "server/api/routes.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/common/error.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/terrain_world.hpp"
#include "maps/dem_digest.hpp"
#include "maps/dem_import_options.hpp"
#include "maps/georef.hpp"
#include "server/api/mission_file.hpp"
#include "server/api/json_body.hpp"
#include "server/api/mission_map_file.hpp"
#include "server/api/multipart.hpp"
#include "server/api/openapi.hpp"
#include "server/problems/problem_builder.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/pdm_json.hpp"
#include "server/json/plan_json.hpp"
#include "server/json/zones_json.hpp"
#include "server/store/disk_budget.hpp"
#include "server/api/zone_routes.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;
using http::Request;
using http::Response;
using nlohmann::json;
namespace rj = rover::json;

namespace {

// A core validation error with its field qualified by `prefix` (e.g. "params."); an error that
// names no field is attributed to `fallback` (every error names its field). The error table
// (error_table.hpp) answers it.
Error qualified(const Error& e, const std::string& prefix = "", const std::string& fallback = "body") {
  return Error(e.code(), e.field().empty() ? fallback : prefix + e.field(), e.what());
}

json mapJson(const store::MapRecord& m) {
  json j = m.meta;
  j["id"] = m.id;
  j["name"] = m.name;
  j["created_at"] = m.createdAt;
  j["layers"] = json::object();
  for (const char* l : {"elevation", "hillshade", "slope", "traversability", "pdm"})
    j["layers"][l] = "/api/maps/" + m.id + "/layers/" + l + ".png";
  return j;
}

json pdmJson(const store::PdmRecord& p) {
  json j = p.meta;
  j["id"] = p.id;
  j["map"] = p.mapId;
  j["name"] = p.name;
  j["created_at"] = p.createdAt;
  j["layer"] = "/api/maps/" + p.mapId + "/layers/pdm.png?pdm=" + p.id;
  j["raster"] = "/api/maps/" + p.mapId + "/layers/pdm.tif?pdm=" + p.id;
  return j;
}

json missionJson(const store::MissionRecord& m) {
  return {{"id", m.id},          {"map", m.mapId},          {"pdm", m.pdmId.empty() ? json(nullptr) : json(m.pdmId)},
          {"label", m.label},
          {"map_name", m.mapName.empty() ? json(nullptr) : json(m.mapName)},
          {"pdm_name", m.pdmName.empty() ? json(nullptr) : json(m.pdmName)},
          {"planner", m.planner}, {"status", m.status},      {"message", m.message},
          {"created_at", m.createdAt}, {"started_at", m.startedAt}, {"finished_at", m.finishedAt},
          {"metrics", m.metrics}, {"spec", m.spec},
          {"links",
           {{"stream", "/api/missions/" + m.id + "/stream"},
            {"result_json", "/api/missions/" + m.id + "/result.json"},
            {"result_geojson", "/api/missions/" + m.id + "/result.geojson"},
            {"result_csv", "/api/missions/" + m.id + "/result.csv"},
            {"map_png", "/api/missions/" + m.id + "/map.png"},
            {"map_tif", "/api/missions/" + m.id + "/map.tif"}}}};
}

double queryNumber(const Request& req, const std::string& key, double fallback) {
  auto it = req.query.find(key);
  if (it == req.query.end() || it->second.empty()) return fallback;
  char* end = nullptr;
  double v = std::strtod(it->second.c_str(), &end);
  if (*end != '\0' || !std::isfinite(v))
    throw ApiError(400, "invalid_parameter", key + " must be a number", key);
  return v;
}

// An integer query parameter in [lo, hi], range-checked as a double before the conversion (a
// static_cast<int> of 1e300 is undefined behaviour).
long long queryInteger(const Request& req, const std::string& key, long long fallback, long long lo, long long hi) {
  const double v = queryNumber(req, key, static_cast<double>(fallback));
  if (v < static_cast<double>(lo) || v > static_cast<double>(hi) || std::trunc(v) != v)
    throw ApiError(400, "invalid_parameter",
                   key + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", key);
  return static_cast<long long>(v);
}

// Listing pages: ?limit= (default 50, at most 500) and ?offset= (rows skipped). The body stays a
// JSON array; X-Total-Count holds the total and, when more rows follow, a Link header
// <path?limit=L&offset=O>; rel="next" (RFC 8288) points at the next page.
constexpr long long kDefaultPage = 50, kMaxPage = 500;
struct Page {
  long long limit, offset;
};
Page pageOf(const Request& req) {
  return {queryInteger(req, "limit", kDefaultPage, 1, kMaxPage), queryInteger(req, "offset", 0, 0, 1'000'000'000)};
}
Response pageResponse(const Request& req, const Page& page, json items, long long total) {
  const long long next = page.offset + static_cast<long long>(items.size());
  Response r = Response::json(200, items);
  r.headers.emplace_back("X-Total-Count", std::to_string(total));
  if (!items.empty() && next < total)
    r.headers.emplace_back("Link", "<" + req.path + "?limit=" + std::to_string(page.limit) +
                                       "&offset=" + std::to_string(next) + ">; rel=\"next\"");
  return r;
}

// Invalidates a map's cached body when the write that changes it has finished, on success or
// failure (after, not before: see ApiContext::mapCacheTicket).
struct InvalidateMapAfter {
  ApiContext& ctx;
  std::string id;
  ~InvalidateMapAfter() { ctx.invalidateMap(id); }
};

// A JSON route's body. The media type must be application/json (parameters such as charset
// allowed): a browser sends text/plain, form-urlencoded or multipart cross-site without asking
// first (no CORS preflight), so accepting those would let any page launch or rename missions
// on an open server.
}  // namespace

json jsonBody(const Request& req, const rj::JsonLimits& limits) {
  std::string type = req.header("content-type");
  type = type.substr(0, type.find(';'));
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
  while (!type.empty() && (type.back() == ' ' || type.back() == '\t')) type.pop_back();
  while (!type.empty() && (type.front() == ' ' || type.front() == '\t')) type.erase(0, 1);
  if (type != "application/json")
    throw ApiError(415, "unsupported_media_type",
                   "send the body as JSON with Content-Type: application/json" +
                       (type.empty() ? std::string(" (the request has none)") : " (not " + rj::shown(type) + ")"),
                   "content-type");
  return rj::parseJsonLimited(req.body, limits);
}

namespace {

std::string queryString(const Request& req, const std::string& key) {
  auto it = req.query.find(key);
  return it == req.query.end() ? "" : it->second;
}

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
    for (const auto& p : splitMultipart(req.bodyFile, boundary, parts)) {
      if (p.filename.empty()) {
        if (p.name == "name" && name.empty()) name = p.value;
        if (auto o = options.find(p.name); o != options.end() && o->second.empty()) o->second = p.value;
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

// The digest of a map's grid (maps/dem_digest): stored with maps imported since mission files,
// computed from the loaded grid for older ones.
std::string mapDigest(ApiContext& ctx, const std::string& mapId) {
  if (auto rec = ctx.db.getMap(mapId); rec && rec->meta.contains("dem_sha256"))
    return rec->meta["dem_sha256"].get<std::string>();
  return maps::demSha256(ctx.maps.get(mapId)->dem);
}

// Builds the planning problem for a mission request; every error names its field.
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
  const Planner* planner = &ctx.planners.get(job.record.planner);
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
  // What the planner plans on: the coverage planner a grid world (the map resampled to its
  // cell); the team planners the map at its own resolution and the PDM. Its memory is estimated
  // and checked against the mission budget first (413 / 429 before anything big is built). Then
  // it is built once to validate and dropped: a queued mission holds only its request, and a
  // worker builds the world again when it starts the mission (MissionJob::build).
  const GridGeometry mapGeometry = ctx.maps.get(job.record.mapId)->dem.geometry();
  rj::checkZonesOnMap(job.problem.keepOut, mapGeometry, "keep_out");
  const int roverCount = static_cast<int>(job.problem.rovers.size());
  problems::MapGround ground;
  try {
    ground = problems::groundOnMap(job.record.planner, mapGeometry, job.params);
  } catch (const Error& e) {
    throw qualified(e, "params.");
  }
  if (ground.coverageGrid) {
    const double cell = ground.cell;
    const double cells = std::ceil(mapGeometry.heightMetres() / cell - 1e-9) *
                         std::ceil(mapGeometry.widthMetres() / cell - 1e-9);
    // The steps bound the moves, so the estimate covers the mission however long it runs.
    const auto steps = missions::coverageStepBudget(job.params, ground.coverage.maxSteps,
                                                    static_cast<std::int64_t>(cells), roverCount);
    job.memory = missions::coverageMissionMemory(static_cast<std::int64_t>(cells), cell, roverCount,
                                                 ground.coverage.mode == coverage::TeamMode::Voronoi,
                                                 steps, ground.coverage.localisation.active());
  } else {
    try {
      job.memory = missions::teamMissionMemory(mapGeometry.cellCount(), roverCount, !job.record.pdmId.empty(),
                                               job.params, job.record.planner == "hybrid");
    } catch (const Error& e) {
      throw qualified(e, "params.");
    }
  }
  ctx.missions.admit(job.memory);
  job.build = [&maps = ctx.maps, ground](missions::MissionJob& j) {
    auto dem = maps.demAtCell(j.record.mapId, 0);
    const terrain::Body body = maps.get(j.record.mapId)->body;
    std::shared_ptr<const Raster<float>> pdm;
    if (!ground.coverageGrid && !j.record.pdmId.empty())
      pdm = maps.pdmMass(j.record.pdmId);
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
    planner->validate(job.problem, job.params);
    job.eventGrid = planner->eventGrid(job.problem, job.params);
  } catch (const Error& e) {
    bool roverField = e.field().rfind("rovers", 0) == 0 || e.field() == "map" || e.field() == "pdm";
    throw qualified(e, roverField || e.field().empty() ? "" : "params.");
  }
  job.record.spec = std::move(request.spec);
  job.record.spec["dem_sha256"] = digest;
  job.problem.world = {};
  job.problem.dem.reset();
  job.problem.pdm.reset();
  return job;
}

// `blocking`: the handler is slow (GDAL, rendering, PDM discretisation, whole-DEM validation)
// and runs on the server's work pool, so the io threads keep answering (see RouteOptions).
constexpr bool onPool = true;

// A route's summary and OpenAPI operation (server/api/openapi.hpp: its statuses and schemas).
http::RouteOptions doc(const std::string& summary, const openapi::Operation& op, bool blocking = false) {
  http::RouteOptions o;
  o.summary = summary;
  o.blocking = blocking;
  o.openapi = op.toJson();
  return o;
}
using openapi::Operation;
using openapi::ref;
const json kId = {{"type", "string"}};

Response fileResponse(const std::string& path, const std::string& type) {
  Response r;
  r.file = path;
  r.contentType = type;
  return r;
}

}  // namespace


Response submitMission(ApiContext& ctx, const json& body) {
  missions::MissionJob job = buildMission(ctx, body);
  job.record.id = store::DataDir::newId();
  job.record.createdAt = store::nowIso();
  const std::string id = job.record.id;
  ctx.missions.submit(std::move(job));
  return Response::json(202, missionJson(*ctx.db.getMission(id)));
}
http::RouteOptions routeDoc(const std::string& summary, const openapi::Operation& op, bool blocking) {
  return doc(summary, op, blocking);
}

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
  }, doc("This document.", Operation().returns(200, "The OpenAPI 3.0.3 document.", {{"type", "object"}})));

  router.add("GET", "/api/planners", [&ctx](const Request& req) {
    // ?map=ID: the defaults that come from that map (coverage cell, the body's gravity) filled in.
    ParamSet mapDefaults;
    json mapInfo;
    if (const std::string id = queryString(req, "map"); !id.empty()) {
      if (!ctx.db.getMap(id)) throw ApiError(404, "not_found", "no map '" + rj::shown(id) + "'", "map");
      auto map = ctx.maps.get(id);
      const terrain::Body body = map->body;
      mapDefaults = coverage::coverageMapDefaults(map->dem.geometry(), body);
      mapInfo = {{"map", id}, {"body", terrain::bodyName(body)}};
    }
    json out = json::array();
    for (const auto& name : ctx.planners.names()) {
      const Planner& p = ctx.planners.get(name);
      json params = rj::toJson(p.params());
      json defaults = mapInfo;
      if (name == "coverage")
        for (auto& info : params)
          if (auto d = mapDefaults.find(info["key"].get<std::string>()); d != mapDefaults.end())
            info["default"] = defaults[d->first] = rj::toJson(d->second);
      json entry{{"name", name}, {"summary", p.summary()}, {"params", params}, {"presets", rj::toJson(p.presets())}};
      if (!mapInfo.is_null()) entry["map_defaults"] = defaults;
      out.push_back(std::move(entry));
    }
    return Response::json(200, out);
  }, doc("Registered planners with every parameter, its default, unit and range; ?map=ID fills in "
         "the defaults that come from the map (coverage_cell, gravity) and its body.",
         Operation()
             .query("map", kId, "A map id: fill in the defaults that come from it.")
             .returns(200, "Every planner.", {{"type", "array"}, {"items", ref("Planner")}})
             .errors({404}),
         onPool));

  // --- maps ---
  router.add("GET", "/api/maps", [&ctx](const Request& req) {
    const Page page = pageOf(req);
    json out = json::array();
    for (const auto& m : ctx.db.listMaps(page.limit, page.offset)) out.push_back(mapJson(m));
    return pageResponse(req, page, std::move(out), ctx.db.countMaps());
  }, doc("List maps, oldest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
          Operation().listing("Map")));

  http::RouteOptions upload;
  upload.streamBody = true;
  upload.blocking = onPool;
  upload.summary = "Upload a DEM (raw body with ?filename=, or multipart/form-data with file parts; "
                   "PDS3 .IMG+.LBL pairs as two parts or a zip), ?name=&cell=&crop=|crop_px=&vertical_scale=&body= "
                   "(or plain multipart fields of those names).";
  {
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
  }
  router.add("POST", "/api/maps", [&ctx](const Request& req) {
    // The DEM options (maps/dem_import_options: cell, crop, crop_px, vertical_scale, body) as
    // query parameters or plain multipart fields, read by the CLI's own parser.
    std::string name = queryString(req, "name");
    std::map<std::string, std::string> options;
    for (const auto& info : maps::demImportOptionInfos()) options[info.key] = queryString(req, info.key);
    auto files = uploadedFiles(req, ctx.dir, name, options);
    try {
      rj::checkName(name, "name");
      for (const auto& [key, value] : options)
        if (value.size() > 200) throw ApiError(400, "invalid_parameter", key + " is longer than 200 bytes", key);
      maps::DemImport import;
      try {
        import = maps::parseDemImportOptions(options);
      } catch (const Error& e) {
        throw qualified(e);
      }
      return Response::json(201, mapJson(ctx.maps.importDem(files, name, import)));
    } catch (...) {
      for (auto& f : files) store::DataDir::removeTree(f.path);
      throw;
    }
  }, upload);

  router.add("GET", "/api/maps/{id}", [&ctx](const Request& req) {
    const std::string& id = req.params.at("id");
    Response r;
    {
      std::lock_guard lock(ctx.mapCacheMutex);
      if (auto it = ctx.mapBodyCache.find(id); it != ctx.mapBodyCache.end()) {
        r.body = it->second;
        return r;
      }
    }
    const std::uint64_t ticket = ctx.mapCacheTicket();  // before the reads
    auto m = ctx.db.getMap(id);
    if (!m) throw ApiError(404, "not_found", "no map '" + rj::shown(id) + "'", "id");
    json j = mapJson(*m);
    // The first kMaxPage PDMs; pdms_total says when /api/maps/{id}/pdms holds more.
    j["pdms"] = json::array();
    for (const auto& p : ctx.db.listPdms(m->id, kMaxPage, 0)) j["pdms"].push_back(pdmJson(p));
    j["pdms_total"] = ctx.db.countPdms(m->id);
    r = Response::json(200, j);
    ctx.cacheMapBody(id, r.body, ticket);
    return r;
  }, doc("One map: size, cell size, CRS, elevation range, class percentages, its first 500 PDMs "
          "(pdms_total counts them all).",
          Operation().returns(200, "The map.", ref("Map")).errors({404})));

  router.add("DELETE", "/api/maps/{id}", [&ctx](const Request& req) {
    InvalidateMapAfter after{ctx, req.params.at("id")};
    ctx.maps.remove(req.params.at("id"));
    return Response::json(200, {{"deleted", req.params.at("id")}});
  }, doc("Delete a map and its PDMs (missions keep their records and results).",
          Operation().returns(200, "Deleted.", ref("Deleted")).errors({404, 503}), onPool));

  router.add("GET", "/api/maps/{id}/layers/{file}", [&ctx](const Request& req) {
    const std::string file = req.params.at("file");
    auto dot = file.rfind('.');
    if (dot == std::string::npos) throw ApiError(404, "not_found", "layer files are NAME.png|tif|f32", "file");
    const std::string layer = file.substr(0, dot), format = file.substr(dot + 1);
    // Range-checked before the conversion; the catalog narrows it to the sizes it renders.
    const int max = static_cast<int>(queryInteger(req, "max", 0, 0, 1'000'000));
    std::string path = ctx.maps.layerFile(req.params.at("id"), layer, format, max, queryString(req, "pdm"));
    Response r = fileResponse(path, format == "png" ? "image/png" : format == "tif" ? "image/tiff" : "application/octet-stream");
    if (format == "f32") {
      auto map = ctx.maps.get(req.params.at("id"));
      const GridGeometry& g = map->dem.geometry();
      r.headers = {{"X-Rows", std::to_string(g.rows)}, {"X-Cols", std::to_string(g.cols)},
                   {"X-Cell-Width-M", std::to_string(g.cellWidth)}, {"X-Cell-Height-M", std::to_string(g.cellHeight)},
                   {"X-Nodata", "NaN"}, {"X-Byte-Order", "little-endian"}};
    }
    r.headers.emplace_back("Cache-Control", "max-age=3600");
    return r;
  }, doc("A layer (elevation|hillshade|slope|traversability|pdm) as .png (?max= overview), "
                   ".tif (GeoTIFF) or .f32 (raw little-endian float32, size in X-Rows/X-Cols); ?pdm=ID for pdm.",
          Operation()
              .query("max", {{"type", "integer"}, {"minimum", 0}, {"maximum", 16384}},
                     "PNG overview: longest side rounded up to 256, 512, 1024, 2048 or 4096.")
              .query("pdm", kId, "The PDM of a pdm layer (default: the newest).")
              .returns(200, "The layer file.", nullptr, "image/png")
              .returns(200, "The layer file.", nullptr, "image/tiff")
              .returns(200, "The layer file.", nullptr, "application/octet-stream")
              .errors({400, 404, 503, 507}),
          onPool));

  addZoneRoutes(router, ctx);  // GET|PUT /api/maps/{id}/zones

  // --- PDMs ---
  router.add("GET", "/api/maps/{id}/pdms", [&ctx](const Request& req) {
    const std::string& id = req.params.at("id");
    if (!ctx.db.getMap(id)) throw ApiError(404, "not_found", "no map '" + rj::shown(id) + "'", "id");
    const Page page = pageOf(req);
    json out = json::array();
    for (const auto& p : ctx.db.listPdms(id, page.limit, page.offset)) out.push_back(pdmJson(p));
    return pageResponse(req, page, std::move(out), ctx.db.countPdms(id));
  }, doc("List a map's PDMs, oldest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
          Operation().listing("Pdm").errors({404})));

  http::RouteOptions pdmUpload;
  pdmUpload.streamBody = true;
  pdmUpload.blocking = onPool;
  pdmUpload.summary = "Create a PDM: JSON {name, components:[{x,y,sigma_x,sigma_y,rotation_deg,weight}]} "
                      "or {name, random: G, seed: S}, or a raster body (any GDAL format) of weights.";
  pdmUpload.openapi = Operation()
                          .query("name", {{"type", "string"}}, "A raster body's PDM name.")
                          .query("filename", {{"type", "string"}}, "A raster body's file name.")
                          .body(ref("PdmRequest"))
                          .body({{"type", "string"}, {"format", "binary"}}, "application/octet-stream")
                          .returns(201, "Created.", ref("Pdm"))
                          .errors({400, 404, 413, 503, 507})
                          .toJson();
  router.add("POST", "/api/maps/{id}/pdms", [&ctx](const Request& req) {
    const std::string mapId = req.params.at("id");
    ctx.maps.get(mapId);  // 404 for an unknown map
    ctx.dir.budget().requireRoom(store::DiskUse::Pdm, mapId, "body");  // 507 before any work
    InvalidateMapAfter after{ctx, mapId};
    if (req.bodyFile.empty() || req.bodySize == 0) throw ApiError(400, "invalid_input", "the request has no body", "body");
    std::string type = req.header("content-type");
    if (type.rfind("application/json", 0) == 0) {
      const auto& limits = rj::kPdmJsonLimits;
      if (req.bodySize > limits.maxBytes)
        throw ApiError(413, "payload_too_large",
                       "PDM JSON over " + std::to_string(limits.maxBytes >> 10) + " KiB", "body");
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
        } catch (const Error& e) {
          throw qualified(e, "", "components");
        }
        meta = {{"kind", "gaussians"}};
      }
      meta["components"] = rj::toJson(comps)["components"];
      return Response::json(201, pdmJson(ctx.maps.createPdm(mapId, name, comps, meta)));
    }
    const std::string name = queryString(req, "name");
    rj::checkName(name, "name");
    const std::string moved = (fs::path(ctx.dir.tmpDir()) / (store::DataDir::newId() + fs::path(queryString(req, "filename")).extension().string())).string();
    fs::rename(req.bodyFile, moved);
    try {
      auto rec = ctx.maps.createPdmFromRaster(mapId, name, moved);
      store::DataDir::removeTree(moved);
      return Response::json(201, pdmJson(rec));
    } catch (...) {
      store::DataDir::removeTree(moved);
      throw;
    }
  }, pdmUpload);

  router.add("GET", "/api/maps/{id}/pdms/{pdm}", [&ctx](const Request& req) {
    auto p = ctx.db.getPdm(req.params.at("pdm"));
    if (!p || p->mapId != req.params.at("id")) throw ApiError(404, "not_found", "no PDM '" + rj::shown(req.params.at("pdm")) + "' on this map", "pdm");
    return Response::json(200, pdmJson(*p));
  }, doc("One PDM.", Operation().returns(200, "The PDM.", ref("Pdm")).errors({404})));

  router.add("DELETE", "/api/maps/{id}/pdms/{pdm}", [&ctx](const Request& req) {
    auto p = ctx.db.getPdm(req.params.at("pdm"));
    if (!p || p->mapId != req.params.at("id")) throw ApiError(404, "not_found", "no PDM '" + rj::shown(req.params.at("pdm")) + "' on this map", "pdm");
    InvalidateMapAfter after{ctx, p->mapId};
    ctx.db.deletePdm(p->id);
    ctx.dir.remove(ctx.dir.pdmDir(p->id));
    return Response::json(200, {{"deleted", p->id}});
  }, doc("Delete a PDM.", Operation().returns(200, "Deleted.", ref("Deleted")).errors({404})));

  // --- missions ---
  router.add("POST", "/api/missions", [&ctx](const Request& req) {
    return submitMission(ctx, jsonBody(req, rj::kMissionJsonLimits));
  }, doc("Launch a mission {map, pdm?, planner, rovers:[{x,y,heading}], params:{...}, pace?}; "
                   "validated fully, then queued (202). A mission file (GET .../mission.json) is accepted as it is.",
          Operation()
              .body({{"anyOf", {ref("MissionRequest"), ref("MissionFile")}}})
              .returns(202, "Queued.", ref("Mission"))
              .errors({400, 409, 413, 415, 429, 503, 507}),
          onPool));

  router.add("GET", "/api/missions", [&ctx](const Request& req) {
    const Page page = pageOf(req);
    json out = json::array();
    for (const auto& m : ctx.db.listMissions(page.limit, page.offset)) out.push_back(missionJson(m));
    return pageResponse(req, page, std::move(out), ctx.db.countMissions());
  }, doc("List missions, newest first: ?limit= (50, at most 500), ?offset=; X-Total-Count and Link rel=next.",
          Operation().listing("Mission")));

  router.add("GET", "/api/missions/{id}", [&ctx](const Request& req) {
    auto m = ctx.db.getMission(req.params.at("id"));
    if (!m) throw ApiError(404, "not_found", "no mission '" + rj::shown(req.params.at("id")) + "'", "id");
    json j = missionJson(*m);
    if (auto s = ctx.missions.stream(m->id)) {
      json live = s->summary();
      j["progress"] = live["progress"];
      j["step"] = live["step"];
    }
    return Response::json(200, j);
  }, doc("One mission: status, progress, metrics.", Operation().returns(200, "The mission.", ref("Mission")).errors({404})));

  router.add("DELETE", "/api/missions/{id}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id");
    auto m = ctx.db.getMission(id);
    if (!m) throw ApiError(404, "not_found", "no mission '" + rj::shown(id) + "'", "id");
    if (ctx.missions.cancel(id)) return Response::json(202, {{"id", id}, {"status", "cancelling"}});
    // Not running (any more): the run is deleted, its row first so no listing shows a run whose
    // files are half gone. A mission that is still finishing cannot be deleted yet.
    if (!store::isFinal(m->status))
      throw ApiError(409, "not_finished", "mission " + rj::shown(id) + " is " + m->status + ": try again when it has ended", "id");
    // Only the request whose delete removed the row says so; a concurrent one finds nothing.
    if (!ctx.db.deleteMission(id)) throw ApiError(404, "not_found", "no mission '" + rj::shown(id) + "'", "id");
    ctx.missions.forget(id);
    ctx.dir.remove(ctx.dir.missionDir(id));
    return Response::json(200, {{"deleted", id}});
  }, doc("Cancel a queued or running mission (202; the planner stops within one step), or delete "
          "an ended one with its result files (200).",
          Operation()
              .returns(200, "Deleted (it had ended).", ref("Deleted"))
              .returns(202, "Cancelling (it was queued or running).", ref("Cancelling"))
              .errors({404, 409})));

  router.add("PATCH", "/api/missions/{id}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id");
    json body = jsonBody(req, rj::kMissionJsonLimits);
    if (!body.is_object()) throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
    for (const auto& item : body.items())
      if (item.key() != "label")
        throw ApiError(400, "unknown_field", "only 'label' can be changed, not '" + rj::shown(item.key()) + "'",
                       rj::shown(item.key()));
    auto label = body.find("label");
    if (label == body.end() || !label->is_string())
      throw ApiError(400, "invalid_field", "label must be a string", "label");
    rj::checkName(label->get<std::string>(), "label");
    // A DELETE may land between the update and the read back: then it is gone (404).
    auto m = ctx.db.setMissionLabel(id, label->get<std::string>()) ? ctx.db.getMission(id) : std::nullopt;
    if (!m) throw ApiError(404, "not_found", "no mission '" + rj::shown(id) + "'", "id");
    return Response::json(200, missionJson(*m));
  }, doc("Rename a run: {\"label\": \"...\"} (at most 200 characters, no control characters).",
          Operation().body(ref("MissionLabel")).returns(200, "Renamed.", ref("Mission")).errors({400, 404, 415})));

  router.add("GET", "/api/missions/{id}/{file}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id"), file = req.params.at("file");
    auto m = ctx.db.getMission(id);
    if (!m) throw ApiError(404, "not_found", "no mission '" + rj::shown(id) + "'", "id");
    if (file == "mission.json") {
      // Recorded at launch; runs launched before that name their map's current grid.
      std::string digest;
      if (m->spec.is_object() && m->spec.contains("dem_sha256") && m->spec["dem_sha256"].is_string())
        digest = m->spec["dem_sha256"].get<std::string>();
      else if (ctx.db.getMap(m->mapId))
        digest = mapDigest(ctx, m->mapId);
      Response r = Response::json(200, missionFile(*m, digest, ctx.version));
      r.headers.emplace_back("Content-Disposition", "attachment; filename=\"mission-" + id + ".json\"");
      return r;
    }
    if (file == "map.png" || file == "map.tif") {
      Response r = fileResponse(missionMapFile(ctx, *m, file.substr(4)), file == "map.png" ? "image/png" : "image/tiff");
      r.headers.emplace_back("Content-Disposition", "attachment; filename=\"mission-" + id + "-" + file + "\"");
      return r;
    }
    static const std::map<std::string, std::string> types{{"result.json", "application/json"},
                                                          {"result.geojson", "application/geo+json"},
                                                          {"result.csv", "text/csv"}};
    auto t = types.find(file);
    if (t == types.end())
      throw ApiError(404, "not_found",
                     "no file '" + rj::shown(file) + "' (mission.json, result.json, result.geojson, result.csv, map.png, map.tif)",
                     "file");
    const fs::path path = fs::path(ctx.dir.missionDir(id)) / file;
    if (!fs::exists(path)) {
      // An ended run without files (failed, cancelled before it stored anything) will never
      // have them: say so, with the reason it ended.
      if (store::isFinal(m->status))
        throw ApiError(409, "no_result",
                       "mission " + rj::shown(id) + " ended " + m->status + " without a result" +
                           (m->message.empty() ? std::string() : ": " + m->message),
                       "id");
      throw ApiError(409, "not_ready", "mission " + rj::shown(id) + " is " + m->status + ": no result yet", "id");
    }
    Response r = fileResponse(path.string(), t->second);
    r.headers.emplace_back("Content-Disposition", "attachment; filename=\"mission-" + id + "-" + file + "\"");
    return r;
  }, doc("A mission's file (mission.json: everything to run it again, POST it to /api/missions), or "
          "a finished mission's result: result.json, result.geojson (map CRS: tracks, route, targets, "
          "zones, incidents), result.csv (every sample, both frames), map.png (the map with its "
          "legend and scale bar, at most 4096 px a side), map.tif (the same map as a GeoTIFF in the "
          "map's CRS).",
          Operation()
              .returns(200, "mission.json (MissionFile), result.json, result.geojson or result.csv.",
                       {{"oneOf", {ref("MissionFile"), {{"type", "object"}, {"required", {"planner", "metrics"}}}}}})
              .returns(200, "result.geojson.", {{"type", "object"}}, "application/geo+json")
              .returns(200, "result.csv.", {{"type", "string"}}, "text/csv")
              .returns(200, "map.png.", nullptr, "image/png")
              .returns(200, "map.tif.", nullptr, "image/tiff")
              .errors({404, 409, 503}),
          onPool));

  http::RouteOptions ws;
  ws.openapi = Operation().errors({404, 503}).toJson();  // 503: subscriber limits (ws_admission.hpp)
  ws.summary = "WebSocket: a snapshot, then live events (binary grid frames, JSON poses/progress), "
               "then {\"type\":\"done\"}; see README for the protocol.";
  router.addWebSocket("/api/missions/{id}/stream", [&ctx](const Request& req, std::shared_ptr<http::WsConnection> c) {
    auto s = ctx.missions.stream(req.params.at("id"));
    if (!s) throw ApiError(404, "not_found", "no mission '" + rj::shown(req.params.at("id")) + "'", "id");
    return s->subscribe(std::move(c));
  }, ws);

  if (ctx.studies) addStudyRoutes(router, ctx);
}

}  // namespace rover::api
