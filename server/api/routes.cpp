#include "server/api/routes.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/common/error.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/terrain_world.hpp"
#include "server/api/multipart.hpp"
#include "server/json/pdm_json.hpp"
#include "server/json/plan_json.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;
using http::Request;
using http::Response;
using nlohmann::json;
namespace rj = rover::json;

namespace {

json parseJsonBody(const Request& req) {
  json j = json::parse(req.body, nullptr, false);
  if (j.is_discarded()) throw ApiError(400, "bad_json", "the request body is not valid JSON", "body");
  if (!j.is_object()) throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  return j;
}

// An ApiError for a core validation error; `prefix` qualifies the field (e.g. "params.").
ApiError fromCore(const Error& e, const std::string& prefix = "") {
  std::string code = errorCodeName(e.code());
  int status = e.code() == ErrorCode::NotFound ? 400 : 400;
  std::string field = e.field().empty() ? "" : prefix + e.field();
  return ApiError(status, code, e.what(), field);
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
          {"planner", m.planner}, {"status", m.status},      {"message", m.message},
          {"created_at", m.createdAt}, {"started_at", m.startedAt}, {"finished_at", m.finishedAt},
          {"metrics", m.metrics}, {"spec", m.spec},
          {"links",
           {{"stream", "/api/missions/" + m.id + "/stream"},
            {"result_json", "/api/missions/" + m.id + "/result.json"},
            {"result_geojson", "/api/missions/" + m.id + "/result.geojson"},
            {"result_csv", "/api/missions/" + m.id + "/result.csv"}}}};
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
                                        std::string& cell) {
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
        if (p.name == "cell" && cell.empty()) cell = p.value;
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

// Builds the planning problem for a mission request; every error names its field.
missions::MissionJob buildMission(ApiContext& ctx, const json& body) {
  static const std::vector<std::string> known{"map", "pdm", "planner", "rovers", "params", "pace", "name"};
  for (const auto& [key, value] : body.items())
    if (std::find(known.begin(), known.end(), key) == known.end())
      throw ApiError(400, "unknown_field", "unknown field '" + key + "'", key);
  auto str = [&](const char* key, bool required) -> std::string {
    auto it = body.find(key);
    if (it == body.end() || it->is_null()) {
      if (required) throw ApiError(400, "missing_field", std::string(key) + " is required", key);
      return "";
    }
    if (!it->is_string()) throw ApiError(400, "invalid_field", std::string(key) + " must be a string", key);
    return it->get<std::string>();
  };
  missions::MissionJob job;
  job.record.mapId = str("map", true);
  job.record.pdmId = str("pdm", false);
  job.record.planner = str("planner", true);
  const Planner* planner = nullptr;
  try {
    planner = &ctx.planners.get(job.record.planner);
  } catch (const Error& e) {
    throw ApiError(400, "unknown_planner", e.what(), "planner");
  }
  if (!ctx.db.getMap(job.record.mapId))
    throw ApiError(400, "not_found", "no map '" + job.record.mapId + "'", "map");
  if (!job.record.pdmId.empty()) {
    auto p = ctx.db.getPdm(job.record.pdmId);
    if (!p || p->mapId != job.record.mapId)
      throw ApiError(400, "not_found", "no PDM '" + job.record.pdmId + "' on this map", "pdm");
  }
  // Parameters: typed by the planner's own table; unknown keys rejected.
  json params = body.value("params", json::object());
  if (!params.is_object()) throw ApiError(400, "invalid_field", "params must be an object", "params");
  auto infos = planner->params();
  for (const auto& item : params.items()) {
    // Not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
    const std::string& key = item.key();
    const json& value = item.value();
    auto info = std::find_if(infos.begin(), infos.end(), [&](const ParamInfo& i) { return i.key == key; });
    if (info == infos.end())
      throw ApiError(400, "unknown_parameter", "unknown parameter '" + key + "' for planner " + job.record.planner,
                     "params." + key);
    try {
      job.params[key] = rj::paramFromJson(*info, value);
    } catch (const Error& e) {
      throw fromCore(e, "params.");
    }
  }
  // Rovers in the local frame (metres from the lower-left corner), heading in degrees.
  auto rovers = body.find("rovers");
  if (rovers == body.end() || !rovers->is_array() || rovers->empty() || rovers->size() > 64)
    throw ApiError(400, "invalid_field", "rovers must be an array of 1 to 64 {x, y, heading}", "rovers");
  for (std::size_t k = 0; k < rovers->size(); ++k) {
    const json& r = (*rovers)[k];
    const std::string f = "rovers[" + std::to_string(k) + "]";
    if (!r.is_object()) throw ApiError(400, "invalid_field", f + " must be an object {x, y, heading}", f);
    for (const char* key : {"x", "y"})
      if (!r.contains(key) || !r[key].is_number())
        throw ApiError(400, "invalid_field", f + "." + key + " must be a number", f + "." + key);
    if (r.contains("heading") && !r["heading"].is_number())
      throw ApiError(400, "invalid_field", f + ".heading must be a number (degrees)", f + ".heading");
    job.problem.rovers.push_back({{r["x"].get<double>(), r["y"].get<double>()},
                                  r.value("heading", 0.0) * std::numbers::pi / 180.0});
  }
  if (body.contains("pace")) {
    if (!body["pace"].is_number() || body["pace"].get<double>() < 0 || body["pace"].get<double>() > 1e6)
      throw ApiError(400, "invalid_field", "pace must be a number of steps per second in [0, 1e6]", "pace");
    job.pace = body["pace"].get<double>();
  }
  // What the planner plans on: the coverage planner a grid world (the map resampled to its
  // cell); the team planners the map at its own resolution and the PDM.
  if (job.record.planner == "coverage") {
    double cell = 1.0;
    try {
      cell = coverage::parseCoverageParams(job.params).coverageCell;
    } catch (const Error& e) {
      throw fromCore(e, "params.");
    }
    auto dem = ctx.maps.demAtCell(job.record.mapId, cell);
    job.problem.world = coverage::worldFromDem(*dem);
    job.geo = dem->z.geo;
    job.mapGrid = dem->geometry();
  } else {
    auto dem = ctx.maps.demAtCell(job.record.mapId, 0);
    job.problem.dem = dem;
    if (!job.record.pdmId.empty())
      job.problem.pdm = std::make_shared<Raster<float>>(ctx.maps.pdmMass(job.record.pdmId));
    job.geo = dem->z.geo;
    job.mapGrid = dem->geometry();
  }
  try {
    planner->validate(job.problem, job.params);
    job.eventGrid = planner->eventGrid(job.problem, job.params);
  } catch (const Error& e) {
    bool roverField = e.field().rfind("rovers", 0) == 0 || e.field() == "map" || e.field() == "pdm";
    throw fromCore(e, roverField || e.field().empty() ? "" : "params.");
  }
  json spec = body;
  spec.erase("map");
  spec.erase("pdm");
  spec.erase("planner");
  job.record.spec = spec;
  return job;
}

// `blocking`: the handler is slow (GDAL, rendering, PDM discretisation, whole-DEM validation)
// and runs on the server's work pool, so the io threads keep answering (see RouteOptions).
constexpr bool onPool = true;

http::RouteOptions doc(const std::string& summary, bool blocking = false) {
  http::RouteOptions o;
  o.summary = summary;
  o.blocking = blocking;
  return o;
}

Response fileResponse(const std::string& path, const std::string& type) {
  Response r;
  r.file = path;
  r.contentType = type;
  return r;
}

}  // namespace

void addApiRoutes(http::Router& router, ApiContext& ctx) {
  http::RouteOptions open;
  open.requireAuth = false;
  open.summary = "Liveness and a few counters (no token needed).";
  router.add("GET", "/api/health", [&ctx](const Request&) {
    return Response::json(200, {{"status", "ok"},
                                {"version", ctx.version},
                                {"maps", ctx.db.listMaps().size()},
                                {"missions_running", ctx.missions.running()},
                                {"missions_queued", ctx.missions.queued()},
                                {"planners", ctx.planners.names()}});
  }, open);

  router.add("GET", "/api/openapi.json", [&router, &ctx](const Request&) {
    return Response::json(200, openApiDocument(router, ctx.version));
  }, doc("This document."));

  router.add("GET", "/api/planners", [&ctx](const Request&) {
    json out = json::array();
    for (const auto& name : ctx.planners.names()) {
      const Planner& p = ctx.planners.get(name);
      out.push_back({{"name", name}, {"summary", p.summary()}, {"params", rj::toJson(p.params())}});
    }
    return Response::json(200, out);
  }, doc("Registered planners with every parameter, its default, unit and range."));

  // --- maps ---
  router.add("GET", "/api/maps", [&ctx](const Request&) {
    json out = json::array();
    for (const auto& m : ctx.db.listMaps()) out.push_back(mapJson(m));
    return Response::json(200, out);
  }, doc("List maps."));

  http::RouteOptions upload;
  upload.streamBody = true;
  upload.blocking = onPool;
  upload.summary = "Upload a DEM (raw body with ?filename=, or multipart/form-data with file parts; "
                   "PDS3 .IMG+.LBL pairs as two parts or a zip), ?name=&cell=.";
  router.add("POST", "/api/maps", [&ctx](const Request& req) {
    std::string name = queryString(req, "name"), cellText = queryString(req, "cell");
    auto files = uploadedFiles(req, ctx.dir, name, cellText);
    double cell = 0;
    if (!cellText.empty()) {
      char* end = nullptr;
      cell = std::strtod(cellText.c_str(), &end);
      if (*end != '\0' || !std::isfinite(cell) || cell < 0) {
        for (auto& f : files) store::DataDir::removeTree(f.path);
        throw ApiError(400, "invalid_parameter", "cell must be a positive number of metres", "cell");
      }
    }
    try {
      return Response::json(201, mapJson(ctx.maps.importDem(files, name, cell)));
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
    auto m = ctx.db.getMap(id);
    if (!m) throw ApiError(404, "not_found", "no map '" + id + "'", "id");
    json j = mapJson(*m);
    j["pdms"] = json::array();
    for (const auto& p : ctx.db.listPdms(m->id)) j["pdms"].push_back(pdmJson(p));
    r.body = j.dump();
    std::lock_guard lock(ctx.mapCacheMutex);
    ctx.mapBodyCache[id] = r.body;
    return r;
  }, doc("One map: size, cell size, CRS, elevation range, class percentages, PDMs."));

  router.add("DELETE", "/api/maps/{id}", [&ctx](const Request& req) {
    ctx.invalidateMap(req.params.at("id"));
    ctx.maps.remove(req.params.at("id"));
    return Response::json(200, {{"deleted", req.params.at("id")}});
  }, doc("Delete a map and its PDMs (missions keep their records and results).", onPool));

  router.add("GET", "/api/maps/{id}/layers/{file}", [&ctx](const Request& req) {
    const std::string file = req.params.at("file");
    auto dot = file.rfind('.');
    if (dot == std::string::npos) throw ApiError(404, "not_found", "layer files are NAME.png|tif|f32", "file");
    const std::string layer = file.substr(0, dot), format = file.substr(dot + 1);
    int max = static_cast<int>(queryNumber(req, "max", 0));
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
                   ".tif (GeoTIFF) or .f32 (raw little-endian float32, size in X-Rows/X-Cols); ?pdm=ID for pdm.", onPool));

  // --- PDMs ---
  router.add("GET", "/api/maps/{id}/pdms", [&ctx](const Request& req) {
    if (!ctx.db.getMap(req.params.at("id"))) throw ApiError(404, "not_found", "no map '" + req.params.at("id") + "'", "id");
    json out = json::array();
    for (const auto& p : ctx.db.listPdms(req.params.at("id"))) out.push_back(pdmJson(p));
    return Response::json(200, out);
  }, doc("List a map's PDMs."));

  http::RouteOptions pdmUpload;
  pdmUpload.streamBody = true;
  pdmUpload.blocking = onPool;
  pdmUpload.summary = "Create a PDM: JSON {name, components:[{x,y,sigma_x,sigma_y,rotation_deg,weight}]} "
                      "or {name, random: G, seed: S}, or a raster body (any GDAL format) of weights.";
  router.add("POST", "/api/maps/{id}/pdms", [&ctx](const Request& req) {
    const std::string mapId = req.params.at("id");
    ctx.maps.get(mapId);  // 404 for an unknown map
    ctx.invalidateMap(mapId);
    if (req.bodyFile.empty() || req.bodySize == 0) throw ApiError(400, "invalid_input", "the request has no body", "body");
    std::string type = req.header("content-type");
    if (type.rfind("application/json", 0) == 0) {
      if (req.bodySize > (4u << 20)) throw ApiError(413, "payload_too_large", "PDM JSON over 4 MiB", "body");
      std::ifstream in(req.bodyFile);
      json j = json::parse(in, nullptr, false);
      if (j.is_discarded() || !j.is_object()) throw ApiError(400, "bad_json", "the body is not a JSON object", "body");
      std::string name = j.value("name", "");
      std::vector<pdm::Gaussian> comps;
      json meta;
      if (j.contains("random")) {
        if (!j["random"].is_number_integer() || j["random"].get<int>() < 1 || j["random"].get<int>() > 100)
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
          throw fromCore(e);
        }
        meta = {{"kind", "gaussians"}};
      }
      meta["components"] = rj::toJson(comps)["components"];
      return Response::json(201, pdmJson(ctx.maps.createPdm(mapId, name, comps, meta)));
    }
    const std::string moved = (fs::path(ctx.dir.tmpDir()) / (store::DataDir::newId() + fs::path(queryString(req, "filename")).extension().string())).string();
    fs::rename(req.bodyFile, moved);
    try {
      auto rec = ctx.maps.createPdmFromRaster(mapId, queryString(req, "name"), moved);
      store::DataDir::removeTree(moved);
      return Response::json(201, pdmJson(rec));
    } catch (...) {
      store::DataDir::removeTree(moved);
      throw;
    }
  }, pdmUpload);

  router.add("GET", "/api/maps/{id}/pdms/{pdm}", [&ctx](const Request& req) {
    auto p = ctx.db.getPdm(req.params.at("pdm"));
    if (!p || p->mapId != req.params.at("id")) throw ApiError(404, "not_found", "no PDM '" + req.params.at("pdm") + "' on this map", "pdm");
    return Response::json(200, pdmJson(*p));
  }, doc("One PDM."));

  router.add("DELETE", "/api/maps/{id}/pdms/{pdm}", [&ctx](const Request& req) {
    auto p = ctx.db.getPdm(req.params.at("pdm"));
    if (!p || p->mapId != req.params.at("id")) throw ApiError(404, "not_found", "no PDM '" + req.params.at("pdm") + "' on this map", "pdm");
    ctx.invalidateMap(p->mapId);
    ctx.db.deletePdm(p->id);
    store::DataDir::removeTree(ctx.dir.pdmDir(p->id));
    return Response::json(200, {{"deleted", p->id}});
  }, doc("Delete a PDM."));

  // --- missions ---
  router.add("POST", "/api/missions", [&ctx](const Request& req) {
    json body = parseJsonBody(req);
    missions::MissionJob job = buildMission(ctx, body);
    job.record.id = store::DataDir::newId();
    job.record.createdAt = store::nowIso();
    const std::string id = job.record.id;
    ctx.missions.submit(std::move(job));
    return Response::json(202, missionJson(*ctx.db.getMission(id)));
  }, doc("Launch a mission {map, pdm?, planner, rovers:[{x,y,heading}], params:{...}, pace?}; "
                   "validated fully, then queued (202).", onPool));

  router.add("GET", "/api/missions", [&ctx](const Request&) {
    json out = json::array();
    for (const auto& m : ctx.db.listMissions()) out.push_back(missionJson(m));
    return Response::json(200, out);
  }, doc("List missions, newest first."));

  router.add("GET", "/api/missions/{id}", [&ctx](const Request& req) {
    auto m = ctx.db.getMission(req.params.at("id"));
    if (!m) throw ApiError(404, "not_found", "no mission '" + req.params.at("id") + "'", "id");
    json j = missionJson(*m);
    if (auto s = ctx.missions.stream(m->id)) {
      json live = s->summary();
      j["progress"] = live["progress"];
      j["step"] = live["step"];
    }
    return Response::json(200, j);
  }, doc("One mission: status, progress, metrics."));

  router.add("DELETE", "/api/missions/{id}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id");
    auto m = ctx.db.getMission(id);
    if (!m) throw ApiError(404, "not_found", "no mission '" + id + "'", "id");
    if (ctx.missions.cancel(id)) return Response::json(202, {{"id", id}, {"status", "cancelling"}});
    return Response::json(409, {{"error", {{"code", "not_running"}, {"message", "mission " + id + " is " + m->status + ", not running"}, {"field", "id"}}}});
  }, doc("Cancel a queued or running mission (the planner stops within one step)."));

  router.add("GET", "/api/missions/{id}/{file}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id"), file = req.params.at("file");
    auto m = ctx.db.getMission(id);
    if (!m) throw ApiError(404, "not_found", "no mission '" + id + "'", "id");
    static const std::map<std::string, std::string> types{{"result.json", "application/json"},
                                                          {"result.geojson", "application/geo+json"},
                                                          {"result.csv", "text/csv"}};
    auto t = types.find(file);
    if (t == types.end()) throw ApiError(404, "not_found", "no file '" + file + "' (result.json, result.geojson, result.csv)", "file");
    const fs::path path = fs::path(ctx.dir.missionDir(id)) / file;
    if (!fs::exists(path))
      throw ApiError(409, "not_ready", "mission " + id + " is " + m->status + ": no result yet", "id");
    Response r = fileResponse(path.string(), t->second);
    r.headers.emplace_back("Content-Disposition", "attachment; filename=\"mission-" + id + "-" + file + "\"");
    return r;
  }, doc("A finished mission's result: result.json, result.geojson (map CRS), result.csv."));

  http::RouteOptions ws;
  ws.summary = "WebSocket: a snapshot, then live events (binary grid frames, JSON poses/progress), "
               "then {\"type\":\"done\"}; see README for the protocol.";
  router.addWebSocket("/api/missions/{id}/stream", [&ctx](const Request& req, std::shared_ptr<http::WsConnection> c) {
    auto s = ctx.missions.stream(req.params.at("id"));
    if (!s) throw ApiError(404, "not_found", "no mission '" + req.params.at("id") + "'", "id");
    return s->subscribe(std::move(c));
  }, ws);
}

json openApiDocument(const http::Router& router, const std::string& version) {
  json paths = json::object();
  const json error = {{"description", "Error"},
                      {"content", {{"application/json", {{"schema", {{"$ref", "#/components/schemas/Error"}}}}}}}};
  for (const auto& r : router.routes()) {
    json op{{"summary", r.options.summary}};
    json params = json::array();
    for (std::size_t p = r.pattern.find('{'); p != std::string::npos; p = r.pattern.find('{', p + 1)) {
      auto end = r.pattern.find('}', p);
      params.push_back({{"name", r.pattern.substr(p + 1, end - p - 1)}, {"in", "path"}, {"required", true},
                        {"schema", {{"type", "string"}}}});
    }
    if (!params.empty()) op["parameters"] = params;
    op["responses"] = {{"200", {{"description", "OK"}}}, {"400", error}, {"404", error}};
    if (r.options.requireAuth) op["security"] = json::array({{{"bearer", json::array()}}});
    if (r.method == "WS") op["responses"]["101"] = {{"description", "Switching to WebSocket"}};
    for (const auto& [k, v] : r.options.openapi.items()) op[k] = v;
    std::string method = r.method == "WS" ? "get" : r.method;
    std::transform(method.begin(), method.end(), method.begin(), [](unsigned char c) { return std::tolower(c); });
    paths[r.pattern][method] = op;
  }
  return {{"openapi", "3.0.3"},
          {"info", {{"title", "roverplan API"}, {"version", version},
                    {"description", "Mission planning for teams of planetary micro-rovers."}}},
          {"paths", paths},
          {"components",
           {{"securitySchemes", {{"bearer", {{"type", "http"}, {"scheme", "bearer"}}}}},
            {"schemas",
             {{"Error",
               {{"type", "object"},
                {"properties",
                 {{"error",
                   {{"type", "object"},
                    {"properties", {{"code", {{"type", "string"}}}, {"message", {{"type", "string"}}},
                                    {"field", {{"type", "string"}}}}}}}}}}}}}}}};
}

}  // namespace rover::api
