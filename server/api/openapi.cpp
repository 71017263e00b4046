#include "server/api/openapi.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "server/api/openapi_kit.hpp"
#include "server/json/plan_json.hpp"

namespace rover::api::openapi {

using nlohmann::json;
using namespace kit;

json ref(const std::string& name) { return {{"$ref", "#/components/schemas/" + name}}; }

namespace {

std::string errorText(int status) {
  switch (status) {
    case 400: return "Bad input; the error's field names it.";
    case 401: return "Missing or wrong bearer token (server started with --token).";
    case 403: return "A state change or live stream asked for by another site's page (its Origin); "
                     "start the server with --cors ORIGIN to allow one.";
    case 404: return "No such resource (the field names which).";
    case 409: return "Conflict with the resource's state (not ready, not finished, another map).";
    case 412: return "version_conflict: the object changed since the version named (If-Match or \"version\"); "
                     "nothing was written, error.current holds the object as stored now.";
    case 428: return "precondition_required: the object exists and the write named no version (If-Match or "
                     "\"version\"), so it could overwrite another operator's change.";
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
  if (name == "layer") return "The layer: elevation, hillshade, slope, traversability or pdm.";
  if (name == "z") return "The tile's zoom, 0 (the whole map in one tile) to the map's tiles.zmax, in decimal digits.";
  if (name == "x") return "The tile's column from the left, from 0, in decimal digits.";
  if (name == "y") return "The tile's row from the top, from 0, and its format: Y.png, or Y.f32 (elevation, slope).";
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

Operation& Operation::ifMatch() {
  op_["parameters"].push_back(
      {{"name", "If-Match"},
       {"in", "header"},
       {"required", false},
       {"description", "The version this write was read at, as its ETag: \"v<N>\" (or a \"version\" member in the "
                       "body). A stale one is answered 412 with the current object; a write to an object that "
                       "exists without either is answered 428."},
       {"schema", {{"type", "string"}, {"pattern", "^\"?v(0|[1-9][0-9]{0,15})\"?$"}}}});
  return *this;
}

Operation& Operation::etag() {
  return header("ETag", "string", "The object's version, \"v<N>\": send it back in If-Match to change it.");
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
      errorResponses[std::to_string(e)] = {
          {"description", errorText(e)},
          {"content", {{"application/json", {{"schema", openapi::ref(e == 412 ? "VersionConflict" : "Error")}}}}}};
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
      if (extra.contains("x-messages")) websockets[r.pattern]["messages"] = extra["x-messages"];
      continue;
    }
    std::string method = r.method;
    std::transform(method.begin(), method.end(), method.begin(), [](unsigned char c) { return std::tolower(c); });
    json op{{"summary", shortSummary(r.options.summary)},
            {"description", r.options.summary},
            {"operationId", operationId(r.method, r.pattern)},
            {"tags", {tagOf(r.pattern)}}};
    for (const auto& q : extra.value("parameters", json::array())) params.push_back(q);
    // Who is asking (issue 26): events and history say it (a named token's name wins).
    if (r.options.requireAuth && r.method != "GET")
      params.push_back({{"name", "X-Operator"},
                        {"in", "header"},
                        {"required", false},
                        {"description", "The operator's name for events and history when the token names none: at "
                                        "most 40 printable characters (400 naming X-Operator otherwise)."},
                        {"schema", {{"type", "string"}, {"maxLength", 160}}}});
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
            {"schemas", componentSchemas(planners)}}}};
}

}  // namespace rover::api::openapi
