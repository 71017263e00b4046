#include "server/api/openapi.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/pdm/pdm.hpp"
#include "maps/dem_import_options.hpp"
#include "server/api/mission_file.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/plan_json.hpp"
#include "server/json/planner_json.hpp"
#include "server/json/zones_json.hpp"
#include "server/store/run_status.hpp"

namespace rover::api::openapi {

using nlohmann::json;

json ref(const std::string& name) { return {{"$ref", "#/components/schemas/" + name}}; }

namespace {

json nullable(json schema) {
  schema["nullable"] = true;
  return schema;
}
json str(const std::string& description = "") {
  json s{{"type", "string"}};
  if (!description.empty()) s["description"] = description;
  return s;
}
json num(const std::string& description = "") {
  json s{{"type", "number"}};
  if (!description.empty()) s["description"] = description;
  return s;
}
json integer(double min, double max) { return {{"type", "integer"}, {"minimum", min}, {"maximum", max}}; }
json object(json properties, std::vector<std::string> required = {}, bool closed = false) {
  json s{{"type", "object"}, {"properties", std::move(properties)}};
  if (!required.empty()) s["required"] = required;
  if (closed) s["additionalProperties"] = false;
  return s;
}
// A string field whose values are an enum's names, from the enum's one table (enum_names.hpp).
template <NamedEnum E>
json oneOf() {
  return {{"type", "string"}, {"enum", enumNames<E>()}};
}

json name(const std::string& description) {
  json s = str(description + " UTF-8, at most " + std::to_string(rover::json::kMaxNameChars) +
               " characters, no control, zero-width or text-direction characters.");
  s["maxLength"] = rover::json::kMaxNameChars;
  return s;
}

std::string errorText(int status) {
  switch (status) {
    case 400: return "Bad input; the error's field names it.";
    case 401: return "Missing or wrong bearer token (server started with --token).";
    case 403: return "A state change or live stream asked for by another site's page (its Origin); "
                     "start the server with --cors ORIGIN to allow one.";
    case 404: return "No such resource (the field names which).";
    case 409: return "Conflict with the resource's state (not ready, not finished, another map).";
    case 413: return "Too large (body, upload, mission memory estimate, an import's memory/CPU/file limits, "
                     "or one object larger than a map's disk budget).";
    case 415: return "The body is not sent as application/json.";
    case 421: return "The Host header names a host this server does not answer to (a DNS-rebinding "
                     "guard); start it with --public-name NAME to add one.";
    case 426: return "A WebSocket path asked for without the upgrade.";
    case 429: return "Mission queue or memory budget full; see Retry-After.";
    case 503: return "Work queue full, or a stream's or the server's subscriber limit reached; see Retry-After.";
    case 507: return "The server's disk is full, or a disk budget (per map or in all) is: the message says which.";
    default: return "Internal error (details in the server log).";
  }
}

// Component name of a planner's parameters: "Params_coverage", "Params_team-search".
std::string paramsComponent(const std::string& planner) { return "Params_" + planner; }

json paramInfoSchema() {
  return object({{"key", str()},
                 {"type", {{"type", "string"}, {"enum", {"bool", "int", "real", "choice", "real_list"}}}},
                 {"default", json::object()},
                 {"unit", str()},
                 {"doc", str()},
                 {"min", num()},
                 {"max", num()},
                 {"choices", {{"type", "array"}, {"items", str()}}},
                 {"group", str("The form's section (route, RRT*, coordination, rover, simulation, ...).")},
                 {"level", {{"type", "string"}, {"enum", {"common", "advanced"}}}}},
                {"key", "type", "default", "unit", "doc", "group", "level"});
}

// A plan's result.json as server/json/plan_json.cpp writes it (the outcome fields in full).
json planResultSchema() {
  json incident = object({{"kind", oneOf<IncidentKind>()},
                          {"rover", {{"type", "integer"}}},
                          {"other", {{"type", "integer"}}},
                          {"time_s", num()},
                          {"step", {{"type", "integer"}}},
                          {"x", num("Metres, local frame.")},
                          {"y", num("Metres, local frame.")},
                          {"note", str()},
                          {"distance_m", num("collision: the closest distance.")},
                          {"max_angle_deg", num("exceedance: the worst |roll| or |pitch|.")},
                          {"cell", {{"type", "integer"}, {"description", "bump: the cell driven into."}}},
                          {"target", {{"type", "integer"}, {"description", "short, skipped, no_slot: the route target."}}}},
                         {"kind", "rover", "x", "y", "note"});
  json target = object({{"target", {{"type", "integer"}}},
                        {"x", num()},
                        {"y", num()},
                        {"status", oneOf<TargetStatus>()},
                        {"legs_reached", {{"type", "integer"}}},
                        {"legs_short", {{"type", "integer"}}},
                        {"legs_skipped", {{"type", "integer"}}},
                        {"legs_no_slot", {{"type", "integer"}}}},
                       {"target", "x", "y", "status"});
  return object({{"planner", str()},
                 {"stop_reason", oneOf<StopReason>()},
                 {"cancelled", {{"type", "boolean"}}},
                 {"metrics", {{"type", "object"}, {"additionalProperties", num()}}},
                 {"metric_units", {{"type", "object"}, {"additionalProperties", str()}}},
                 {"rovers", {{"type", "array"}, {"items", {{"type", "object"}}}}},
                 {"series", {{"type", "object"}}},
                 {"warnings", {{"type", "array"}, {"items", str()}}},
                 {"incidents", {{"type", "array"}, {"items", incident}}},
                 {"targets", {{"type", "array"}, {"items", target}}}},
                {"planner", "stop_reason", "cancelled", "metrics"});
}

json schemas(const PlannerRegistry& planners) {
  json s = json::object();
  s["Error"] = object(
      {{"error", object({{"code", str("Machine-readable, e.g. invalid_field, not_found.")},
                         {"message", str("In words, without server paths.")},
                         {"field", str("The input at fault: a body field (params.targets, rovers[1].x), "
                                       "a query parameter, a header, or the path part.")}},
                        {"code", "message"})}},
      {"error"});

  // Parameters of each planner, from its own table (the same one the request is checked with).
  std::vector<std::string> names = planners.names();
  std::string pdmPlanners;
  for (const auto& n : names)
    if (planners.get(n).specs().ground == Ground::DemAndPdm) pdmPlanners += (pdmPlanners.empty() ? "" : ", ") + n;
  json anyParams = json::array();
  for (const auto& n : names) {
    json props = json::object();
    for (const auto& info : planners.get(n).params()) props[info.key] = paramSchema(info);
    json p = object(props, {}, true);
    p["description"] = "Parameters of " + n + "; any left out take their defaults (GET /api/planners).";
    s[paramsComponent(n)] = p;
    anyParams.push_back(openapi::ref(paramsComponent(n)));
  }

  const double maxXY = rover::json::kMaxCoordinateM, maxHeading = rover::json::kMaxHeadingDeg;
  json rover = object({{"x", {{"type", "number"}, {"minimum", -maxXY}, {"maximum", maxXY},
                              {"description", "Metres east of the map's lower-left corner."}}},
                       {"y", {{"type", "number"}, {"minimum", -maxXY}, {"maximum", maxXY},
                              {"description", "Metres north of the map's lower-left corner."}}},
                       {"heading", {{"type", "number"}, {"minimum", -maxHeading}, {"maximum", maxHeading},
                                    {"description", "Degrees counter-clockwise from east (0)."}}}},
                      {"x", "y"});
  json request = object(
      {{"map", str("Map id.")},
       {"pdm", nullable(str("PDM id on that map: the probability to search, for the planners whose ground is "
                            "dem_pdm (" + pdmPlanners + ")."))},
       {"planner", {{"type", "string"}, {"enum", names}}},
       {"rovers", {{"type", "array"}, {"minItems", 1}, {"maxItems", rover::json::kMaxRovers}, {"items", rover}}},
       {"params", {{"anyOf", anyParams}}},
       {"pace", {{"type", "number"}, {"minimum", 0}, {"maximum", rover::json::kMaxPace},
                 {"description", "Steps per second while watching (0 = full speed)."}}},
       {"name", nullable(name("The run's label."))},
       {"format", {{"type", "string"}, {"enum", {kMissionFileFormat}}}},
       {"version", integer(1, kMissionFileVersion)},
       {"roverplan", nullable(str("The server version that wrote the mission file (informative)."))},
       {"dem_sha256", nullable({{"type", "string"}, {"pattern", "^[0-9a-f]{64}$"},
                                {"description", "The map's grid digest; a map with another answers 409 map_changed."}})},
       {"map_name", nullable(str("Informative."))},
       {"keep_out", {{"type", "object"}, {"allOf", {openapi::ref("Zones")}}, {"nullable", true},
                     {"description", "Keep-out zones of this mission, in the local frame."}}}},
      {"map", "planner", "rovers"}, true);
  // Every field the parser accepts has its schema, and no other.
  for (const char* f : rover::json::kMissionRequestFields)
    if (!request["properties"].contains(f)) throw std::logic_error(std::string("openapi: no schema for ") + f);
  s["MissionRequest"] = request;
  json file = request;
  file["required"] = {"format", "version", "map", "planner", "rovers", "params"};
  file["description"] = "A mission file: everything to run a mission again (POST it to /api/missions).";
  s["MissionFile"] = file;
  // Keep-out zones (server/json/zones_json.hpp): Polygons in the local frame unless ?crs=map.
  json position = {{"type", "array"}, {"items", num()}, {"minItems", 2}, {"maxItems", 3}};
  json ring = {{"type", "array"}, {"items", position}, {"minItems", 4}, {"maxItems", rover::json::kMaxZoneVertices + 1}};
  json polygon = object({{"type", {{"type", "string"}, {"enum", {"Polygon"}}}},
                         {"coordinates", {{"type", "array"}, {"items", ring}, {"minItems", 1}}}},
                        {"type", "coordinates"});
  json feature = object({{"type", {{"type", "string"}, {"enum", {"Feature"}}}},
                         {"geometry", polygon},
                         {"properties", nullable(object({{"name", str()}}))}},
                        {"type", "geometry"});
  s["Zones"] = object({{"type", {{"type", "string"}, {"enum", {"FeatureCollection"}}}},
                       {"features", {{"type", "array"}, {"items", feature}, {"maxItems", rover::json::kMaxZones}}}},
                      {"type", "features"});
  s["Zones"]["description"] = "Keep-out zones: a GeoJSON FeatureCollection of Polygons (at most " +
                              std::to_string(rover::json::kMaxZones) + " zones and " +
                              std::to_string(rover::json::kMaxZoneVertices) + " vertices in all).";
  s["MissionLabel"] = object({{"label", name("The run's new label (\"\" clears it).")}}, {"label"}, true);

  s["Mission"] = object(
      {{"id", str()},
       {"map", str()},
       {"pdm", nullable(str())},
       {"label", str()},
       {"map_name", nullable(str("Null once the map is deleted."))},
       {"pdm_name", nullable(str())},
       {"planner", str()},
       {"status", oneOf<RunStatus>()},
       {"message", str("Why it failed, or its warnings.")},
       {"created_at", str()},
       {"started_at", str()},
       {"finished_at", str()},
       {"metrics", nullable({{"type", "object"}, {"additionalProperties", num()}})},
       {"spec", {{"type", "object"}, {"description", "The request as accepted, with the map's dem_sha256 at launch."}}},
       {"links", object({{"stream", str()}, {"result_json", str()}, {"result_geojson", str()}, {"result_csv", str()}},
                        {"stream", "result_json", "result_geojson", "result_csv"})},
       {"progress", nullable(object({{"fraction", num("0..1")}, {"coverage", num()}, {"moves", num()}, {"step", num()}},
                                    {}, false))},
       {"step", nullable(num())},
       {"result", {{"type", "string"},
                   {"enum", {"pending", "ready", "none"}},
                   {"description", "GET of one mission: its result files are to come (queued, running, or a cancelled "
                                   "run storing its partial result: they answer 409 not_ready), there, or never "
                                   "(409 no_result)."}}}},
      {"id", "map", "planner", "status", "message", "created_at", "links", "spec"});
  s.update(studySchemas());
  s["PlanResult"] = planResultSchema();
  s["Cancelling"] = object({{"id", str()}, {"status", {{"type", "string"}, {"enum", {"cancelling"}}}}}, {"id", "status"});
  s["Deleted"] = object({{"deleted", str("The id deleted.")}}, {"deleted"});

  s["Pdm"] = object({{"id", str()},
                     {"map", str()},
                     {"name", str()},
                     {"created_at", str()},
                     {"kind", {{"type", "string"}, {"enum", {"gaussians", "random", "raster"}}}},
                     {"seed", {{"type", "integer"}}},
                     {"components", {{"type", "array"}, {"items", {{"type", "object"}}}}},
                     {"layer", str("PNG of the PDM.")},
                     {"raster", str("GeoTIFF of the PDM.")}},
                    {"id", "map", "name", "created_at", "layer"});
  json component = object({{"x", num("Metres, local frame.")},
                           {"y", num("Metres, local frame.")},
                           {"sigma_x", {{"type", "number"}, {"exclusiveMinimum", true}, {"minimum", 0}}},
                           {"sigma_y", {{"type", "number"}, {"exclusiveMinimum", true}, {"minimum", 0}}},
                           {"rotation_deg", {{"type", "number"}, {"minimum", -360}, {"maximum", 360}}},
                           {"weight", {{"type", "number"}, {"minimum", 0}, {"maximum", 1e9}}}},
                          {"x", "y", "sigma_x"}, true);
  s["PdmRequest"] = object({{"name", nullable(name("The PDM's name."))},
                            {"components", {{"type", "array"}, {"minItems", 1}, {"maxItems", pdm::kMaxComponents},
                                            {"items", component}}},
                            {"random", integer(1, 100)},
                            {"seed", integer(0, 1.8e19)}});

  s["Map"] = object({{"id", str()},
                     {"name", str()},
                     {"created_at", str()},
                     {"rows", {{"type", "integer"}}},
                     {"cols", {{"type", "integer"}}},
                     {"cell_size_m", num()},
                     {"cell_height_m", num()},
                     {"width_m", num()},
                     {"height_m", num()},
                     {"crs", str()},
                     {"geographic", {{"type", "boolean"}}},
                     {"driver", str()},
                     {"source_files", {{"type", "array"}, {"items", str()}}},
                     {"dem_sha256", {{"type", "string"}, {"pattern", "^[0-9a-f]{64}$"}}},
                     {"resampling", str()},
                     {"elevation", object({{"min", num()}, {"max", num()}}, {"min", "max"})},
                     {"classes", object({{"traversable_pct", num()}, {"high_risk_pct", num()},
                                         {"impassable_pct", num()}, {"nodata_pct", num()}})},
                     {"body", {{"type", "string"}, {"enum", {"mars", "moon", "earth", "unknown"}}}},
                     {"body_source", {{"type", "string"}, {"enum", {"declared", "crs"}}}},
                     {"vertical_scale", num()},
                     {"crop", {{"type", "array"}, {"items", num()}, {"minItems", 4}, {"maxItems", 4}}},
                     {"crop_px", {{"type", "array"}, {"items", num()}, {"minItems", 4}, {"maxItems", 4}}},
                     {"layers", {{"type", "object"}, {"additionalProperties", str()}}},
                     {"pdms", {{"type", "array"}, {"items", openapi::ref("Pdm")}}},
                     {"pdms_total", {{"type", "integer"}}}},
                    {"id", "name", "created_at", "rows", "cols", "cell_size_m", "layers"});
  json upload = json::object();
  upload["file"] = {{"type", "array"}, {"items", {{"type", "string"}, {"format", "binary"}}},
                    {"description", "The DEM's files (one or more parts named file: .IMG + .LBL, a zip, ...)."}};
  upload["name"] = name("The map's name (default: from the file).");
  for (const auto& o : maps::demImportOptionInfos())
    upload[o.key] = {{"type", "string"}, {"pattern", o.pattern}, {"description", o.doc}};
  s["MapUpload"] = object(upload, {"file"});

  s["ParamInfo"] = paramInfoSchema();
  s["Preset"] = object({{"name", str()}, {"doc", str()}, {"params", {{"type", "object"}}}}, {"name", "doc", "params"});
  // What each planner describes of itself (core/planning/planner_specs.hpp), with the enums'
  // names from the JSON edge (server/json/planner_json.hpp).
  s["PlannerMetric"] = object({{"key", str()}, {"unit", str("Empty when dimensionless.")}, {"doc", str()}},
                              {"key", "unit", "doc"});
  s["PlannerStage"] = object({{"name", str()}, {"doc", str()}}, {"name", "doc"});
  s["Planner"] = object(
      {{"name", {{"type", "string"}, {"enum", names}}},
       {"summary", str()},
       {"params", {{"type", "array"}, {"items", openapi::ref("ParamInfo")}}},
       {"presets", {{"type", "array"}, {"items", openapi::ref("Preset")}}},
       {"map_defaults", {{"type", "object"}, {"description", "With ?map=: map, body and the defaults it sets."}}},
       {"ground", {{"type", "string"},
                   {"enum", rover::json::groundNames()},
                   {"description", "What it plans on: coverage_grid (the map resampled to its coverage cell, or "
                                   "a random obstacle grid) or dem_pdm (the map at its own resolution and a PDM)."}}},
       {"starts", {{"type", "string"},
                   {"enum", rover::json::startPlacementNames()},
                   {"description", "Where its rovers start when none are placed (a study's runs)."}}},
       {"progress", object({{"measure", {{"type", "string"}, {"enum", rover::json::progressNames()}}},
                            {"series", str("The result's series that records it.")}},
                           {"measure", "series"})},
       {"seconds_per_run", {{"type", "boolean"}, {"description", "A run takes seconds (a simulated mission)."}}},
       {"metrics", {{"type", "array"}, {"items", openapi::ref("PlannerMetric")}}},
       {"stages", {{"type", "array"}, {"items", openapi::ref("PlannerStage")}}}},
      {"name", "summary", "params", "presets", "ground", "starts", "progress", "seconds_per_run", "metrics", "stages"});
  s["Health"] = object({{"status", {{"type", "string"}, {"enum", {"ok"}}}},
                        {"version", str()},
                        {"maps", {{"type", "integer"}}},
                        {"missions_running", {{"type", "integer"}}},
                        {"missions_queued", {{"type", "integer"}}},
                        {"planners", {{"type", "array"}, {"items", str()}}}},
                       {"status", "version", "planners"});
  return s;
}

// The operation's one-line summary: its description up to the first clause break ("List
// missions, newest first: ?limit= ..." -> "List missions, newest first").
std::string shortSummary(const std::string& text) {
  std::size_t cut = text.size();
  for (const char* mark : {": ", "; ", ". ", " (", " {"}) cut = std::min(cut, text.find(mark));
  std::string out = text.substr(0, cut);
  if (out.size() > 60 && out.find(", ") != std::string::npos) out = out.substr(0, out.find(", "));
  while (!out.empty() && out.back() == '.') out.pop_back();
  return out;
}

// Each route's resource, by its path: the most specific one named in it.
std::string tagOf(const std::string& pattern) {
  for (const char* sub : {"/pdms", "/layers", "/zones"})
    if (pattern.find(sub) != std::string::npos) return std::string(sub + 1);
  for (const char* top : {"maps", "missions", "studies", "planners"})
    if (pattern.rfind(std::string("/api/") + top, 0) == 0) return top;
  return "server";
}

json tags() {
  return json::array({{{"name", "server"}, {"description", "Liveness and this document."}},
                      {{"name", "planners"}, {"description", "The registered planners and their parameters."}},
                      {{"name", "maps"}, {"description", "DEMs: upload, metadata, delete."}},
                      {{"name", "layers"}, {"description", "A map's rasters (elevation, slope, classes, PDM)."}},
                      {{"name", "zones"}, {"description", "A map's keep-out zones."}},
                      {{"name", "pdms"}, {"description", "Probability distribution maps of a map."}},
                      {{"name", "missions"}, {"description", "Launch, watch, rename, cancel missions; their files."}},
                      {{"name", "studies"}, {"description", "Seeded batches of runs: launch, summary, downloads."}}});
}

std::string pathParamText(const std::string& name) {
  if (name == "id") return "The resource's id (as its listing gives it).";
  if (name == "pdm") return "The PDM's id.";
  if (name == "run") return "The run's index in the study, in plain decimal digits.";
  if (name == "file") return "The file's name (the route's description lists them).";
  return "A path segment.";
}

std::string operationId(const std::string& method, const std::string& pattern) {
  std::string id = method;
  std::transform(id.begin(), id.end(), id.begin(), [](unsigned char c) { return std::tolower(c); });
  for (char c : pattern) {
    if (std::isalnum(static_cast<unsigned char>(c))) id += c;
    else if (c == '/' || c == '{' || c == '.') id += '_';
  }
  return id;
}

}  // namespace

json paramSchema(const ParamInfo& info) {
  json s;
  switch (info.type) {
    case ParamType::Bool:
      s["type"] = "boolean";
      break;
    case ParamType::Int:
      s["type"] = "integer";
      s["format"] = "int64";
      break;
    case ParamType::Real:
      s["type"] = "number";
      break;
    case ParamType::Choice:
      s["type"] = "string";
      s["enum"] = info.choices;
      break;
    case ParamType::RealList:
      s["type"] = "array";
      s["items"] = {{"type", "number"}};
      break;
  }
  if (info.type == ParamType::Int || info.type == ParamType::Real) {
    if (std::isfinite(info.min)) s["minimum"] = info.min;
    if (std::isfinite(info.max)) s["maximum"] = info.max;
  }
  s["default"] = rover::json::toJson(info.defaultValue);
  s["description"] = info.doc + (info.unit.empty() ? "" : " [" + info.unit + "]");
  return s;
}

Operation& Operation::returns(int status, const std::string& description, json schema, const std::string& contentType) {
  json& r = op_["responses"][std::to_string(status)];
  r["description"] = description;
  if (!schema.is_null() || contentType != "application/json")
    r["content"][contentType]["schema"] = schema.is_null() ? json{{"type", "string"}, {"format", "binary"}} : schema;
  last_ = status;
  return *this;
}

Operation& Operation::header(const std::string& name, const std::string& type, const std::string& description) {
  op_["responses"][std::to_string(last_)]["headers"][name] = {{"description", description}, {"schema", {{"type", type}}}};
  return *this;
}

Operation& Operation::body(json schema, const std::string& contentType) {
  op_["requestBody"]["required"] = true;
  op_["requestBody"]["content"][contentType]["schema"] = std::move(schema);
  return *this;
}

Operation& Operation::query(const std::string& name, json schema, const std::string& description, bool required) {
  op_["parameters"].push_back(
      {{"name", name}, {"in", "query"}, {"required", required}, {"description", description}, {"schema", schema}});
  return *this;
}

Operation& Operation::errors(std::initializer_list<int> statuses) {
  for (int s : statuses) op_["x-errors"].push_back(s);
  return *this;
}

Operation& Operation::listing(const std::string& item) {
  query("limit", integer(1, 500), "Page size (default 50).");
  query("offset", integer(0, 1e9), "Rows skipped.");
  returns(200, "A page of the list.", {{"type", "array"}, {"items", openapi::ref(item)}});
  header("X-Total-Count", "integer", "How many there are in all.");
  header("Link", "string", "<...?limit=L&offset=O>; rel=\"next\" while more follow.");
  return errors({400});
}

json document(const http::Router& router, const PlannerRegistry& planners, const std::string& version) {
  json paths = json::object();
  json websockets = json::object();
  for (const auto& r : router.routes()) {
    json params = json::array();
    for (std::size_t p = r.pattern.find('{'); p != std::string::npos; p = r.pattern.find('{', p + 1)) {
      auto end = r.pattern.find('}', p);
      const std::string name = r.pattern.substr(p + 1, end - p - 1);
      params.push_back({{"name", name}, {"in", "path"}, {"required", true}, {"description", pathParamText(name)},
                        {"schema", {{"type", "string"}}}});
    }
    json extra = r.options.openapi.is_object() ? r.options.openapi : json::object();
    std::vector<int> errors = extra.value("x-errors", std::vector<int>{});
    if (r.options.requireAuth) errors.push_back(401);
    if (r.method != "GET") errors.push_back(403);  // request_origin.hpp: state changes and streams
    errors.push_back(421);
    errors.push_back(500);
    json errorResponses = json::object();
    for (int e : errors)
      errorResponses[std::to_string(e)] = {{"description", errorText(e)},
                                           {"content", {{"application/json", {{"schema", openapi::ref("Error")}}}}}};
    // OpenAPI 3.0 has no way to say "WebSocket": a 101 is no success a linter or a generated client
    // knows. The streams are listed apart, with the errors their upgrade may answer.
    if (r.method == "WS") {
      errorResponses["426"] = {{"description", errorText(426)},
                               {"content", {{"application/json", {{"schema", openapi::ref("Error")}}}}}};
      websockets[r.pattern] = {{"summary", shortSummary(r.options.summary)},
                               {"description", r.options.summary},
                               {"tags", {tagOf(r.pattern)}},
                               {"parameters", params},
                               {"errors", errorResponses}};
      continue;
    }
    std::string method = r.method;
    std::transform(method.begin(), method.end(), method.begin(), [](unsigned char c) { return std::tolower(c); });
    json op{{"summary", shortSummary(r.options.summary)},
            {"description", r.options.summary},
            {"operationId", operationId(r.method, r.pattern)},
            {"tags", {tagOf(r.pattern)}}};
    for (const auto& q : extra.value("parameters", json::array())) params.push_back(q);
    if (!params.empty()) op["parameters"] = params;
    if (extra.contains("requestBody")) op["requestBody"] = extra["requestBody"];
    json responses = extra.value("responses", json::object());
    if (responses.empty()) responses["200"] = {{"description", "OK"}};
    responses.update(errorResponses);
    op["responses"] = responses;
    // Routes that take the token take it only when the server was started with --token: the
    // empty requirement says a server without one answers as well.
    op["security"] = r.options.requireAuth ? json::array({{{"bearer", json::array()}}, json::object()}) : json::array();
    paths[r.pattern][method] = op;
  }
  return {{"openapi", "3.0.3"},
          {"info", {{"title", "roverplan API"}, {"version", version},
                    {"description", "Mission planning for teams of planetary micro-rovers. WebSocket streams "
                                    "(which OpenAPI 3.0 cannot describe) are listed under x-websockets."},
                    {"contact", {{"name", "The operator of this roverplan server"}}},
                    // The project declares no licence yet: say what that means, not a licence it has not chosen.
                    {"license", {{"name", "No licence declared (all rights reserved)"},
                                 {"url", "https://choosealicense.com/no-permission/"}}}}},
          {"servers", json::array({{{"url", "http://{host}:{port}"},
                                    {"description", "A roverplan server (`roverplan serve`, loopback by default)."},
                                    {"variables", {{"host", {{"default", "127.0.0.1"}}},
                                                   {"port", {{"default", "8080"}}}}}}})},
          {"tags", tags()},
          {"paths", paths},
          {"x-websockets", websockets},
          {"components",
           {{"securitySchemes",
             {{"bearer", {{"type", "http"}, {"scheme", "bearer"},
                          {"description", "Authorization: Bearer TOKEN, when the server was started with --token "
                                          "TOKEN (a WebSocket upgrade may give ?token=TOKEN instead)."}}}}},
            {"schemas", schemas(planners)}}}};
}

}  // namespace rover::api::openapi
