// /api/studies (issue 12): launch, list, watch, download and cancel studies; a run opened as a
// mission. The studies themselves are run by studies::StudyManager.
#include <charconv>
#include <cmath>

#include "core/common/error.hpp"
#include "server/api/mission_service.hpp"
#include "server/api/preconditions.hpp"
#include "server/api/route_kit.hpp"
#include "server/errors/domain_error.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"
#include "server/json/plan_json.hpp"
#include "server/problems/problem_builder.hpp"
#include "server/studies/studies.hpp"

namespace rover::api {


namespace {

// A study document is small (a grid of parameter values); 64 KiB as a mission request.
constexpr rj::JsonLimits kStudyJsonLimits{std::size_t{64} << 10, 64};

// The study a POST body asks for: a study document as it is, or {"preset", "runs", "master_seed",
// "name"} made into the preset's document. The server reads no file a request names: DEM worlds
// are refused, and the swinton preset runs on its synthetic Mars world only. Throws DomainError
// for the body's shape, rover::Error naming the field for the document (parseStudySpec).
studies::StudySpec studyOfRequest(const json& body) {
  if (!body.is_object()) throw DomainError(Refusal::BadJson, "the request body must be a JSON object", "body");
  if (body.contains("preset")) {
    for (const auto& item : body.items())
      if (item.key() != "preset" && item.key() != "runs" && item.key() != "master_seed" && item.key() != "name")
        throw DomainError(Refusal::UnknownField, "with a preset only runs, master_seed and name may be given",
                          item.key().substr(0, 64));
    if (!body["preset"].is_string()) throw DomainError(Refusal::InvalidField, "preset must be a string", "preset");
    studies::PresetOptions o;
    o.hirisePath = "";
    if (body.contains("runs")) {
      const json& r = body["runs"];
      if (!r.is_number_integer() || r.get<std::int64_t>() < 1 || r.get<std::int64_t>() > studies::kMaxRuns)
        throw DomainError(Refusal::InvalidField,
                          "runs must be an integer in [1, " + std::to_string(studies::kMaxRuns) + "]", "runs");
      o.runs = r.get<int>();
    }
    if (body.contains("master_seed")) {
      if (!body["master_seed"].is_number_unsigned())
        throw DomainError(Refusal::InvalidField, "master_seed must be a non-negative integer", "master_seed");
      o.masterSeed = body["master_seed"].get<std::uint64_t>();
    }
    json spec = studies::presetSpecJson(body["preset"].get<std::string>(), o);
    if (body.contains("name")) spec["name"] = body["name"];  // checked with the spec, by the name rule
    return studies::parseStudySpec(spec);
  }
  if (const auto w = body.find("worlds"); w != body.end() && w->is_array())
    for (std::size_t i = 0; i < w->size(); ++i)
      if ((*w)[i].is_object() && (*w)[i].contains("dem"))
        throw DomainError(Refusal::InvalidField, "the server reads no file a request names: use grid or terrain worlds",
                          "worlds[" + std::to_string(i) + "].dem");
  return studies::parseStudySpec(body);
}

studies::StudyState studyOr404(ApiContext& ctx, const std::string& id) {
  auto s = ctx.studies->get(id);
  if (!s) throw ApiError(404, "not_found", "no study '" + id + "'", "id");
  return *s;
}

bool sameTerrain(const maps::SyntheticTerrainParams& a, const maps::SyntheticTerrainParams& b) {
  return a.preset == b.preset && a.size == b.size && a.cellSize == b.cellSize && a.seed == b.seed &&
         a.craterDensity == b.craterDensity && a.rockDensity == b.rockDensity && a.relief == b.relief;
}

// The mission a run was, for POST /api/missions, or why there is none. A run on the synthetic Mars
// world of the default map (mars, 600 cells of 0.25 m, seed 1: the map `serve` creates) is a
// mission on that map: the same parameters, the run's seed, the same starts (team: the formation;
// coverage: the random valid starts of the run's seed on the same grid world) and, for a team run,
// its random PDM (G components of the run's seed: pdm::randomGaussians discretised on the cells
// with data, as the study's problem builder does). Grid worlds are random obstacle grids drawn per
// run: no stored map holds one.
json runMission(ApiContext& ctx, const studies::StudySpec& spec, std::size_t runIndex) {
  const studies::Configuration& c = spec.configOf(runIndex);
  const studies::WorldSpec& world = spec.worlds[c.world];
  const std::uint64_t seed = studies::runSeed(spec.masterSeed, spec.replicateOf(runIndex));
  const Planner& planner = ctx.planners.get(c.point.planner);
  const bool onMap = planner.specs().ground == Ground::DemAndPdm;
  json out{{"run_index", runIndex}, {"config", c.name}, {"planner", c.point.planner}, {"world", world.name},
           {"rovers", c.rovers}, {"seed", seed}, {"replicate", spec.replicateOf(runIndex)}};
  json params = json::object();
  for (const auto& [k, v] : c.point.params) params[k] = rj::toJson(v);
  out["params"] = params;
  const auto unavailable = [&](const std::string& why) {
    out["mission"] = nullptr;
    out["mission_unavailable"] = why;
    return out;
  };
  if (world.kind == studies::WorldSpec::Kind::Grid)
    return unavailable("this run's world is a random obstacle grid (" + world.name +
                       ", drawn from the run's seed); missions run on stored maps, so it cannot be opened as one");
  if (world.kind != studies::WorldSpec::Kind::Terrain || !sameTerrain(world.terrain, maps::SyntheticTerrainParams{}))
    return unavailable("only runs on the synthetic Mars world of the default map (mars, 600 cells of 0.25 m, "
                       "seed 1) can be opened as missions");
  std::string mapId;
  for (const auto& m : ctx.db.listMaps())
    if (m.name.rfind("Default: synthetic Mars", 0) == 0) mapId = m.id;
  if (mapId.empty()) return unavailable("the server's default map (synthetic Mars, seed 1) was deleted");
  ParamSet runParams = c.point.params;
  auto dem = ctx.maps.demAtCell(mapId, 0);
  if (onMap && planner.hasParam("seed")) {  // as the study runner gives a run its seed
    runParams["seed"] = static_cast<std::int64_t>(seed);
    params["seed"] = seed;
  }
  const PlanningProblem problem = problems::problemOnMap(planner.groundOnMap(dem->geometry(), runParams), dem);
  const std::vector<RoverStart> starts = planner.defaultStarts(problem, runParams, c.rovers, seed);
  json rovers = json::array();
  for (const auto& r : starts)
    rovers.push_back({{"x", r.position.x()}, {"y", r.position.y()}, {"heading", r.heading * 180.0 / M_PI}});
  out["mission"] = {{"map", mapId}, {"planner", c.point.planner}, {"rovers", rovers}, {"params", params},
                    {"name", spec.name + " · " + c.name + " · run " + std::to_string(runIndex)}};
  if (onMap && spec.pdmComponents > 0) out["pdm_random"] = {{"components", spec.pdmComponents}, {"seed", seed}};
  return out;
}

// A run is named by its index in plain decimal digits ("7", never "7.0", "1e3", "+7" or "07"): one
// run, one address.
std::size_t runIndexOf(const Request& req, const studies::StudySpec& spec) {
  const std::string& text = req.params.at("run");
  std::size_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  const bool canonical = !text.empty() && ec == std::errc() && end == text.data() + text.size() &&
                         (text[0] != '0' || text.size() == 1);
  if (!canonical || v >= spec.runCount())
    throw ApiError(404, "not_found", "run must be an index in [0, " + std::to_string(spec.runCount()) + ")", "run");
  return v;
}

json configurationsJson(const studies::StudySpec& spec) {
  json out = json::array();
  for (const auto& c : spec.configurations) {
    json params = json::object();
    for (const auto& [k, v] : c.point.params) params[k] = rj::toJson(v);
    out.push_back({{"id", c.id}, {"name", c.name}, {"planner", c.point.planner},
                   {"world", spec.worlds[c.world].name}, {"rovers", c.rovers}, {"params", params}});
  }
  return out;
}

// PATCH /api/studies/{id} {"name", "version"?}: a versioned rename, as PATCH /api/missions/{id}.
Response renameStudy(ApiContext& ctx, const Request& req) {
  const std::string id = req.params.at("id");
  json body = jsonBody(req, rj::kMissionJsonLimits);
  const std::string name = newNameOf(body);
  const std::string what = "study " + rj::shown(id);
  studyOr404(ctx, id);
  const long long expected = requiredVersion(req, &body, what);
  std::lock_guard lock(ctx.versionedWrites);
  studies::StudyState s;
  switch (ctx.studies->rename(id, name, expected, s)) {
    case store::Cas::Done: break;
    case store::Cas::Missing: throw ApiError(404, "not_found", "no study '" + rj::shown(id) + "'", "id");
    case store::Cas::Stale: throw versionConflict(what, expected, s.version, studies::toJson(s));
  }
  publishEvent(ctx, "changed", "study", id, "", s.version, req.operatorName);
  return withETag(Response::json(200, studies::toJson(s)), s.version);
}

}  // namespace

void addStudyRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/studies/presets", [](const Request&) {
    json out = json::array();
    for (const auto& name : studies::presetNames()) {
      studies::PresetOptions o;
      o.hirisePath = "";  // the server reads no DEM file a request names
      json spec = studies::presetSpecJson(name, o);
      out.push_back({{"name", name}, {"spec", spec}});
    }
    return Response::json(200, out);
  }, routeDoc("Study presets (laine-fig6, laine-fig8, frontier, swinton) as study documents.",
              Operation().returns(200, "The presets.", {{"type", "array"}, {"items", ref("StudyPreset")}})));

  router.add("POST", "/api/studies", [&ctx](const Request& req) {
    const json body = jsonBody(req, kStudyJsonLimits);
    const studies::StudyState s = ctx.studies->submit(studyOfRequest(body));
    publishEvent(ctx, "created", "study", s.id, "", 0, req.operatorName);
    return Response::json(202, studies::toJson(s));
  }, routeDoc("Launch a study: a study document (see README \"Studies\") or {\"preset\": NAME, \"runs\": N, "
               "\"master_seed\"?, \"name\"?}; validated (400 naming the field), stored and queued (202). At most " +
               std::to_string(studies::kMaxServerRuns) + " runs per study, " + std::to_string(studies::kMaxActive) +
               " studies queued or running, " + std::to_string(studies::kMaxStored) + " kept (429).", Operation().body(ref("StudyRequest")).returns(202, "Queued.", ref("Study")).errors({400, 413, 415, 429, 507}), true));

  router.add("GET", "/api/studies", [&ctx](const Request&) {
    json out = json::array();
    for (const auto& s : ctx.studies->list()) out.push_back(studies::toJson(s));
    return Response::json(200, out);
  }, routeDoc("List studies, newest first: status, runs done/total, ETA.", Operation().returns(200, "Studies", {{"type", "array"}, {"items", openapi::ref("Study")}})));

  router.add("GET", "/api/studies/{id}", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    json j = studies::toJson(s);
    const json spec = ctx.studies->specJson(s.id);
    j["spec"] = spec;
    j["configurations"] = configurationsJson(studies::parseStudySpec(spec));
    j["summary"] = ctx.studies->summary(s.id);
    return withETag(Response::json(200, j), s.version);
  }, routeDoc("One study: its document, configurations, status and summary table (mean, std, quartiles "
               "per configuration and metric; partial while it runs).", Operation().returns(200, "The study.", ref("StudyDetail")).etag().errors({404}), true));

  router.add("PATCH", "/api/studies/{id}", handler(ctx, renameStudy),
             routeDoc("Rename a study: {\"name\": \"...\"} (at most 200 characters, no control characters, not "
                      "blank), naming the version read (If-Match \"v<N>\" or \"version\"): 412 with the current "
                      "study when stale, 428 without one. The study document (spec) keeps the name it was launched with.",
                      Operation()
                          .ifMatch()
                          .body(ref("StudyName"))
                          .returns(200, "Renamed.", ref("Study"))
                          .etag()
                          .errors({400, 404, 412, 415, 428, 507})));

  router.add("DELETE", "/api/studies/{id}", [&ctx](const Request& req) {
    const std::string id = req.params.at("id");
    switch (ctx.studies->remove(id)) {
      case studies::StudyManager::Removal::NotFound: throw ApiError(404, "not_found", "no study '" + id + "'", "id");
      case studies::StudyManager::Removal::Cancelling:
        publishEvent(ctx, "changed", "study", id, "", 0, req.operatorName);
        return Response::json(202, {{"id", id}, {"status", "cancelling"}});
      case studies::StudyManager::Removal::Deleted: break;
    }
    publishEvent(ctx, "deleted", "study", id, "", 0, req.operatorName);
    return Response::json(200, {{"deleted", id}});
  }, routeDoc("Cancel a queued or running study (202; the runs done are kept), or delete an ended one with "
               "its database (200).", Operation().returns(202, "Cancelling.", ref("Cancelling")).returns(200, "Deleted.", ref("Deleted")).errors({404}), true));

  router.add("GET", "/api/studies/{id}/runs.csv", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    return withAttachment(fileResponse(ctx.studies->runsCsvFile(s.id), "text/csv"), "study-" + s.id + "-runs.csv");
  }, routeDoc("The study's runs as CSV: run_index, config, replicate, seed, status, wall_s, cpu_s, host, "
               "rank, then one column per metric.", Operation().returns(200, "Runs", nullptr, "text/csv").errors({404}), true));

  router.add("GET", "/api/studies/{id}/study.sqlite", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    const std::string path = ctx.studies->databasePath(s.id);
    if (path.empty()) throw ApiError(409, "not_ready", "study " + s.id + " has no database yet", "id");
    return withAttachment(fileResponse(path, "application/vnd.sqlite3"), "study-" + s.id + ".sqlite");
  }, routeDoc("The study database (SQLite, WAL: complete once the study has ended): spec, configs, runs, "
               "curves; `roverplan study summary` reads it.", Operation().returns(200, "SQLite database", nullptr, "application/vnd.sqlite3").errors({404, 409})));

  router.add("GET", "/api/studies/{id}/benchmark.db", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    const std::string path = ctx.studies->benchmarkDbFile(s.id);
    if (path.empty()) throw ApiError(409, "not_ready", "study " + s.id + " has no database yet", "id");
    return withAttachment(fileResponse(path, "application/vnd.sqlite3"), "study-" + s.id + "-benchmark.db");
  }, routeDoc("The study as an OMPL benchmark database (SQLite: experiments, plannerConfigs, enums, runs, "
               "progress, as ompl_benchmark_statistics.py writes them; our metrics are run columns): open it "
               "in Planner Arena. The runs stored so far while the study runs.",
               Operation().returns(200, "OMPL benchmark database.", nullptr, "application/vnd.sqlite3").errors({404, 409}),
               onPool));

  router.add("GET", "/api/studies/{id}/runs/{run}", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    const studies::StudySpec spec = studies::parseStudySpec(ctx.studies->specJson(s.id));
    return Response::json(200, runMission(ctx, spec, runIndexOf(req, spec)));
  }, routeDoc("One run: its configuration, parameters, seed and the mission it was (or why it has none: "
               "mission_unavailable).", Operation().returns(200, "The run.", ref("StudyRun")).errors({404}), true));

  router.add("POST", "/api/studies/{id}/runs/{run}/mission", [&ctx](const Request& req) {
    const studies::StudyState s = studyOr404(ctx, req.params.at("id"));
    const studies::StudySpec spec = studies::parseStudySpec(ctx.studies->specJson(s.id));
    json run = runMission(ctx, spec, runIndexOf(req, spec));
    if (run["mission"].is_null())
      throw ApiError(409, "not_a_mission", run["mission_unavailable"].get<std::string>(), "run");
    json body = run["mission"];
    if (run.contains("pdm_random")) {
      // The run's PDM as a PDM of the map, as POST /api/maps/{map}/pdms {random, seed} makes it.
      const std::string mapId = body["map"].get<std::string>();
      const int g = run["pdm_random"]["components"].get<int>();
      const std::uint64_t seed = run["pdm_random"]["seed"].get<std::uint64_t>();
      auto comps = pdm::randomGaussians(ctx.maps.get(mapId)->dem.geometry(), g, seed);
      json meta{{"kind", "random"}, {"seed", seed}};
      meta["components"] = rj::toJson(comps)["components"];
      const store::PdmRecord p = ctx.maps.createPdm(
          mapId, "study run " + std::to_string(run["run_index"].get<std::size_t>()) + " (G = " + std::to_string(g) + ")",
          comps, meta);
      ctx.invalidateMap(mapId);
      body["pdm"] = p.id;
    }
    return Response::json(202, missionJson(submitMission(ctx, body, req.operatorName)));
  }, routeDoc("Open a run as a mission: the same map, planner, parameters, seed, starts (and PDM, created on "
               "the map) queued as a new mission (202, the mission); 409 not_a_mission when the run's world "
               "is no stored map.", Operation().returns(202, "Queued mission.", ref("Mission")).errors({404, 409, 429}), true));

  http::RouteOptions ws = routeDoc("WebSocket: {\"type\":\"snapshot\"}, then progress frames (runs done/total, "
                                   "ETA, a partial summary every few seconds), then {\"type\":\"done\"}.", Operation().returns(101, "Switching protocols").errors({404, 503}));
  router.addWebSocket("/api/studies/{id}/stream", [&ctx](const Request& req, std::shared_ptr<http::WsConnection> c) {
    auto s = ctx.studies->stream(req.params.at("id"));
    if (!s) throw ApiError(404, "not_found", "no study '" + req.params.at("id") + "'", "id");
    return s->subscribe(std::move(c));
  }, ws);
}

}  // namespace rover::api
