// The OpenAPI document is a contract a client can be generated from (issue 13): it is
// structurally valid 3.0.3, every $ref resolves, every route declares the statuses it answers,
// and the answers of the main routes match the schemas the document gives for them (a small
// JSON-schema subset validator below: type, nullable, enum, properties, required,
// additionalProperties, items, minItems/maxItems, minimum/maximum, maxLength, pattern,
// anyOf/oneOf, $ref). Every route is then called, its successes and errors alike, and each
// answer checked against the document: JSON against its schema, files by their media type.
#include <doctest/doctest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <set>

#include "api_server.hpp"
#include "server/json/mission_request.hpp"
#include "server/studies/studies.hpp"
#include "server/studies/study_manager.hpp"
#include "maps/dem_io.hpp"

using rover::ParamType;
using rover::test::ApiServer;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

class SchemaCheck {
 public:
  explicit SchemaCheck(const json& doc) : doc_(doc) {}

  // Problems of `value` against `schema` ("" when it matches), each with its JSON path.
  std::vector<std::string> check(const json& value, const json& schema) const {
    std::vector<std::string> out;
    visit(value, schema, "$", out);
    return out;
  }

  const json& resolve(const json& schema) const {
    if (!schema.contains("$ref")) return schema;
    const std::string ref = schema["$ref"];
    REQUIRE(ref.rfind("#/components/schemas/", 0) == 0);
    const std::string name = ref.substr(21);
    REQUIRE_MESSAGE(doc_["components"]["schemas"].contains(name), ref);
    return doc_["components"]["schemas"][name];
  }

 private:
  static bool isType(const json& v, const std::string& type) {
    if (type == "object") return v.is_object();
    if (type == "array") return v.is_array();
    if (type == "string") return v.is_string();
    if (type == "boolean") return v.is_boolean();
    if (type == "number") return v.is_number();
    if (type == "integer") return v.is_number_integer() || (v.is_number_float() && v.get<double>() == std::trunc(v.get<double>()));
    return false;
  }

  void visit(const json& v, const json& schemaIn, const std::string& at, std::vector<std::string>& out) const {
    const json& s = resolve(schemaIn);
    if (v.is_null()) {
      if (s.contains("type") && !s.value("nullable", false)) out.push_back(at + ": null not allowed");
      return;
    }
    for (const auto& alt : s.value("allOf", json::array())) visit(v, alt, at, out);
    for (const char* k : {"anyOf", "oneOf"}) {
      if (!s.contains(k)) continue;
      int matches = 0;
      for (const auto& alt : s[k]) matches += check(v, alt).empty();
      if (matches == 0 || (std::string(k) == "oneOf" && matches > 1))
        out.push_back(at + ": " + std::to_string(matches) + " of the " + k + " alternatives match");
    }
    if (s.contains("type") && !isType(v, s["type"])) {
      out.push_back(at + ": not of type " + s["type"].get<std::string>() + " (" + v.dump().substr(0, 80) + ")");
      return;
    }
    if (s.contains("enum") && std::find(s["enum"].begin(), s["enum"].end(), v) == s["enum"].end())
      out.push_back(at + ": " + v.dump() + " not in the enum");
    if (v.is_number()) {
      const double d = v.get<double>();
      if (s.contains("minimum") && d < s["minimum"].get<double>()) out.push_back(at + ": below minimum");
      if (s.contains("maximum") && d > s["maximum"].get<double>()) out.push_back(at + ": above maximum");
    }
    if (v.is_string()) {
      const std::string t = v;
      if (s.contains("maxLength") && t.size() > s["maxLength"].get<std::size_t>() * 4) out.push_back(at + ": too long");
      if (s.contains("pattern") && !std::regex_search(t, std::regex(s["pattern"].get<std::string>())))
        out.push_back(at + ": does not match " + s["pattern"].get<std::string>());
    }
    if (v.is_array()) {
      if (s.contains("minItems") && v.size() < s["minItems"].get<std::size_t>()) out.push_back(at + ": too few items");
      if (s.contains("maxItems") && v.size() > s["maxItems"].get<std::size_t>()) out.push_back(at + ": too many items");
      if (s.contains("items"))
        for (std::size_t i = 0; i < v.size(); ++i) visit(v[i], s["items"], at + "[" + std::to_string(i) + "]", out);
    }
    if (v.is_object()) {
      for (const auto& r : s.value("required", json::array()))
        if (!v.contains(r.get<std::string>())) out.push_back(at + ": lacks required " + r.get<std::string>());
      const json props = s.value("properties", json::object());
      for (const auto& [k, item] : v.items()) {
        if (props.contains(k)) visit(item, props[k], at + "." + k, out);
        else if (s.contains("additionalProperties") && s["additionalProperties"].is_boolean() && !s["additionalProperties"].get<bool>())
          out.push_back(at + ": unexpected property " + k);
        else if (s.contains("additionalProperties") && s["additionalProperties"].is_object())
          visit(item, s["additionalProperties"], at + "." + k, out);
      }
    }
  }

  const json& doc_;
};

// The schema the document gives for (path pattern, method, status, content type).
json responseSchema(const json& doc, const std::string& pattern, const std::string& method, int status,
                    const std::string& type = "application/json") {
  const json& op = doc["paths"][pattern][method];
  REQUIRE_MESSAGE(op["responses"].contains(std::to_string(status)), method << " " << pattern << " " << status);
  const json& r = op["responses"][std::to_string(status)];
  REQUIRE_MESSAGE(r.contains("content"), method << " " << pattern << " " << status << " has no content");
  REQUIRE(r["content"].contains(type));
  return r["content"][type]["schema"];
}

struct Contract {
  ApiServer& s;
  json doc;
  SchemaCheck checker{doc};
  std::set<std::string> answered{};  // "get /api/maps/{id}" of every route whose answer was checked
  // Checks an answer's status is documented for the route and its body matches the schema.
  json expect(const rover::test::HttpResult& r, const std::string& pattern, const std::string& method, int status) {
    CHECK_MESSAGE(r.status == status, method << " " << pattern << ": " << r.status << " " << r.body.substr(0, 300));
    const json body = r.json();
    const auto problems = checker.check(body, responseSchema(doc, pattern, method, r.status));
    CHECK_MESSAGE(problems.empty(), method << " " << pattern << " " << r.status << ": " << (problems.empty() ? "" : problems[0]));
    answered.insert(method + " " + pattern);
    return body;
  }
  // A file answer: its status documented with its media type, and sent with that type.
  void expectFile(const rover::test::HttpResult& r, const std::string& pattern, const std::string& method, int status,
                  const std::string& type) {
    CHECK_MESSAGE(r.status == status, method << " " << pattern << ": " << r.status << " " << r.body.substr(0, 300));
    responseSchema(doc, pattern, method, status, type);
    CHECK(r.headers.at("Content-Type").rfind(type, 0) == 0);
    CHECK(!r.body.empty());
    answered.insert(method + " " + pattern);
  }
  // A WebSocket upgrade refused: a status x-websockets lists for the stream, as an Error.
  void expectRefusedUpgrade(const std::string& target, const std::string& pattern, int status) {
    const auto r = request(s.port(), "GET", target, "", "",
                           {{"Upgrade", "websocket"}, {"Connection", "Upgrade"},
                            {"Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="}, {"Sec-WebSocket-Version", "13"}});
    CHECK_MESSAGE(r.status == status, pattern << ": " << r.status);
    const json& doc404 = doc["x-websockets"][pattern]["errors"][std::to_string(r.status)];
    REQUIRE_MESSAGE(doc404.is_object(), pattern << " does not list " << r.status);
    CHECK(checker.check(r.json(), doc404["content"]["application/json"]["schema"]).empty());
    answered.insert("ws " + pattern);
  }
};

}  // namespace

TEST_CASE("openapi: the document is structurally valid 3.0.3 and every $ref resolves") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const json doc = s.get("/api/openapi.json").json();
  REQUIRE(doc.is_object());
  CHECK(doc["openapi"] == "3.0.3");
  CHECK(doc["info"]["title"].is_string());
  CHECK(doc["info"]["version"].is_string());
  const std::set<std::string> methods{"get", "put", "post", "delete", "options", "head", "patch", "trace"};
  std::set<std::string> operationIds;
  const std::regex statusRe("^[1-5][0-9][0-9]$");
  // Named locals, not structured bindings: clang 14 cannot capture one in CHECK_MESSAGE's lambda.
  for (const auto& pathEntry : doc["paths"].items()) {
    const std::string& path = pathEntry.key();
    const json& item = pathEntry.value();
    CHECK(path.rfind("/api/", 0) == 0);
    for (const auto& opEntry : item.items()) {
      const std::string& method = opEntry.key();
      const json& op = opEntry.value();
      CHECK_MESSAGE(methods.count(method), path << " " << method);
      REQUIRE(op.contains("responses"));
      CHECK(!op["responses"].empty());
      const std::string id = op["operationId"];
      CHECK_MESSAGE(operationIds.insert(id).second, "operationId " << id << " is used twice");
      for (const auto& respEntry : op["responses"].items()) {
        const std::string& status = respEntry.key();
        const json& resp = respEntry.value();
        CHECK_MESSAGE(std::regex_match(status, statusRe), path << " " << status);
        CHECK(resp["description"].is_string());
        // Every error answers the Error schema (a 412 its VersionConflict form: Error with the current object).
        if (status[0] == '4' || status[0] == '5')
          CHECK(resp["content"]["application/json"]["schema"]["$ref"] ==
                (status == "412" ? "#/components/schemas/VersionConflict" : "#/components/schemas/Error"));
      }
      // Path parameters declared, once each, required.
      std::set<std::string> declared;
      for (const auto& p : op.value("parameters", json::array())) {
        CHECK(p["schema"].is_object());
        // Headers: If-Match and X-Operator (issue 26).
        CHECK((p["in"] == "path" || p["in"] == "query" ||
               (p["in"] == "header" && (p["name"] == "If-Match" || p["name"] == "X-Operator"))));
        if (p["in"] == "path") {
          CHECK(p["required"] == true);
          declared.insert(p["name"].get<std::string>());
        }
      }
      for (std::size_t a = path.find('{'); a != std::string::npos; a = path.find('{', a + 1))
        CHECK_MESSAGE(declared.count(path.substr(a + 1, path.find('}', a) - a - 1)), path);
      if (op.contains("requestBody")) CHECK(!op["requestBody"]["content"].empty());
    }
  }
  // Every $ref anywhere points at a schema that exists.
  std::function<void(const json&)> refs = [&](const json& j) {
    if (j.is_object()) {
      if (j.contains("$ref")) {
        const std::string r = j["$ref"];
        CHECK_MESSAGE((r.rfind("#/components/schemas/", 0) == 0 && doc["components"]["schemas"].contains(r.substr(21))), r);
      }
      for (const auto& [k, v] : j.items()) refs(v);
    } else if (j.is_array()) {
      for (const auto& v : j) refs(v);
    }
  };
  refs(doc);
  // Real statuses: launches are 202, creations 201, the stream 101.
  CHECK(doc["paths"]["/api/missions"]["post"]["responses"].contains("202"));
  CHECK(!doc["paths"]["/api/missions"]["post"]["responses"].contains("200"));
  CHECK(doc["paths"]["/api/missions"]["post"]["responses"].contains("415"));
  CHECK(doc["paths"]["/api/maps"]["post"]["responses"].contains("201"));
  CHECK(doc["paths"]["/api/maps/{id}/pdms"]["post"]["responses"].contains("201"));
  CHECK(doc["paths"]["/api/missions/{id}"]["delete"]["responses"].contains("202"));
  CHECK(!doc["paths"].contains("/api/missions/{id}/stream"));
  CHECK(doc["x-websockets"]["/api/missions/{id}/stream"]["errors"].contains("404"));
  // The request schemas come from the validation's tables: every planner parameter with its range.
  const json& schemas = doc["components"]["schemas"];
  for (const auto& name : s.planners.names())
    for (const auto& info : s.planners.get(name).params()) {
      const json& p = schemas["Params_" + name]["properties"][info.key];
      CHECK_MESSAGE(p.is_object(), name << "." << info.key);
      if (info.type == ParamType::Real && std::isfinite(info.max)) CHECK(p["maximum"] == info.max);
    }
  for (const char* f : rover::json::kMissionRequestFields) CHECK(schemas["MissionRequest"]["properties"].contains(f));
  CHECK(schemas["MissionRequest"]["properties"]["rovers"]["maxItems"] == rover::json::kMaxRovers);
  CHECK(schemas["MapUpload"]["properties"].contains("crop_px"));
  CHECK(schemas["MapUpload"]["properties"].contains("vertical_scale"));
}

TEST_CASE("openapi: the main routes answer what their schemas say") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  Contract c{s, s.get("/api/openapi.json").json()};
  const json health = c.expect(s.get("/api/health"), "/api/health", "get", 200);
  const json planners = c.expect(s.get("/api/planners"), "/api/planners", "get", 200);
  REQUIRE(planners.size() >= 3);
  const json maps = c.expect(s.get("/api/maps"), "/api/maps", "get", 200);
  const std::string map = maps[0]["id"];
  c.expect(s.get("/api/planners?map=" + map), "/api/planners", "get", 200);
  c.expect(s.get("/api/maps/" + map), "/api/maps/{id}", "get", 200);
  c.expect(s.get("/api/maps/nope"), "/api/maps/{id}", "get", 404);

  // A PDM (201), its listing and itself.
  const json pdmBody = {{"name", "two"}, {"components", {{{"x", 40}, {"y", 60}, {"sigma_x", 8}}, {{"x", 90}, {"y", 30}, {"sigma_x", 5}}}}};
  const auto pdmRequestSchema = c.doc["paths"]["/api/maps/{id}/pdms"]["post"]["requestBody"]["content"]["application/json"]["schema"];
  CHECK(c.checker.check(pdmBody, pdmRequestSchema).empty());
  const json pdm = c.expect(s.postJson("/api/maps/" + map + "/pdms", pdmBody), "/api/maps/{id}/pdms", "post", 201);
  c.expect(s.get("/api/maps/" + map + "/pdms"), "/api/maps/{id}/pdms", "get", 200);
  c.expect(s.get("/api/maps/" + map + "/pdms/" + pdm["id"].get<std::string>()), "/api/maps/{id}/pdms/{pdm}", "get", 200);

  // A mission: the request matches the request schema, the launch is 202.
  const json mission = {{"map", map}, {"planner", "coverage"}, {"pace", 0},
                        {"rovers", {{{"x", 20}, {"y", 20}, {"heading", 0}}}},
                        {"params", {{"coverage", 0.2}, {"pattern", "spiral"}}}};
  const json requestSchema = c.doc["paths"]["/api/missions"]["post"]["requestBody"]["content"]["application/json"]["schema"];
  CHECK(c.checker.check(mission, requestSchema).empty());
  json bad = mission;
  bad["params"]["coverage"] = 7;  // outside the table's range: the schema says so too
  CHECK(!c.checker.check(bad, requestSchema).empty());
  bad = mission;
  bad["colour"] = "red";
  CHECK(!c.checker.check(bad, requestSchema).empty());
  const json launched = c.expect(s.postJson("/api/missions", mission), "/api/missions", "post", 202);
  const std::string id = launched["id"];
  c.expect(s.postJson("/api/missions", bad), "/api/missions", "post", 400);
  c.expect(request(s.port(), "POST", "/api/missions", mission.dump(), "text/plain"), "/api/missions", "post", 415);
  s.waitFinished(id);
  c.expect(s.get("/api/missions/" + id), "/api/missions/{id}", "get", 200);
  c.expect(s.get("/api/missions"), "/api/missions", "get", 200);
  c.expect(request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":"strip A","version":1})", "application/json"),
           "/api/missions/{id}", "patch", 200);
  const json file = c.expect(s.get("/api/missions/" + id + "/mission.json"), "/api/missions/{id}/{file}", "get", 200);
  CHECK(c.checker.check(file, c.checker.resolve(json{{"$ref", "#/components/schemas/MissionFile"}})).empty());
  CHECK(c.checker.check(file, requestSchema).empty());  // a mission file is a request
  c.expect(s.get("/api/missions/" + id + "/result.json"), "/api/missions/{id}/{file}", "get", 200);
  c.expect(s.get("/api/missions/" + id + "/nope.txt"), "/api/missions/{id}/{file}", "get", 404);
  c.expect(request(s.port(), "DELETE", "/api/missions/" + id), "/api/missions/{id}", "delete", 200);
  c.expect(request(s.port(), "DELETE", "/api/maps/" + map + "/pdms/" + pdm["id"].get<std::string>()),
           "/api/maps/{id}/pdms/{pdm}", "delete", 200);
  CHECK(health["planners"].size() == planners.size());
}

namespace {

// The API with studies, as `roverplan serve` builds it.
struct StudyApi {
  ApiServer api;
  rover::studies::StudyManager studies;
  explicit StudyApi(const std::string& data)
      : api(data, [] {
          rover::test::ApiServerOptions o;
          o.start = false;
          return o;
        }()),
        studies(api.dir, [] { return false; }) {
    api.ctx.studies = &studies;
    rover::api::addStudyRoutes(api.router, api.ctx);
    api.start();
  }
  ~StudyApi() { studies.stop(); }
};

// A 40 × 50 GeoTIFF of 1 m cells, as bytes.
std::string smallDem(const TempDir& tmp) {
  rover::Raster<float> z(rover::GridGeometry{40, 50, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 50; ++c) z(r, c) = 0.05f * static_cast<float>(c);
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100040, 0, -1};
  const std::string path = tmp.str("small.tif");
  rover::maps::writeGeoTiff(path, z);
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace

TEST_CASE("openapi: every route answers what the document says, errors included") {
  TempDir tmp;
  StudyApi sa(tmp.str("data"));
  ApiServer& s = sa.api;
  Contract c{s, s.get("/api/openapi.json").json()};
  const auto send = [&](const std::string& method, const std::string& target, const json& body) {
    return request(s.port(), method, target, body.dump(), "application/json");
  };
  c.expect(s.get("/api/openapi.json"), "/api/openapi.json", "get", 200);
  c.expect(s.get("/api/health"), "/api/health", "get", 200);
  c.expect(s.get("/api/planners"), "/api/planners", "get", 200);
  c.expect(s.get("/api/planners?map=nope"), "/api/planners", "get", 404);

  // Maps: an upload (201), a bad one, the listing, one map, its layers, its deletion.
  const std::string map = s.defaultMap();
  const json up = c.expect(request(s.port(), "POST", "/api/maps?name=small&filename=small.tif", smallDem(tmp), "image/tiff"),
                           "/api/maps", "post", 201);
  c.expect(request(s.port(), "POST", "/api/maps?filename=x.tif", "not a raster", "image/tiff"), "/api/maps", "post", 400);
  c.expect(s.get("/api/maps"), "/api/maps", "get", 200);
  c.expect(s.get("/api/maps?limit=0"), "/api/maps", "get", 400);
  c.expect(s.get("/api/maps/" + map), "/api/maps/{id}", "get", 200);
  c.expect(s.get("/api/maps/nope"), "/api/maps/{id}", "get", 404);
  // A map's rename (issue 26): 428 without a version, 200, 412 stale, 400 bad name, 404, 409 taken.
  {
    const std::string small = "/api/maps/" + up["id"].get<std::string>();
    c.expect(send("PATCH", small, {{"name", "small east"}}), "/api/maps/{id}", "patch", 428);
    c.expect(send("PATCH", small, {{"name", "small east"}, {"version", 1}}), "/api/maps/{id}", "patch", 200);
    c.expect(send("PATCH", small, {{"name", "small west"}, {"version", 1}}), "/api/maps/{id}", "patch", 412);
    c.expect(send("PATCH", small, {{"name", ""}, {"version", 2}}), "/api/maps/{id}", "patch", 400);
    c.expect(send("PATCH", "/api/maps/nope", {{"name", "x"}, {"version", 1}}), "/api/maps/{id}", "patch", 404);
    c.expect(send("PATCH", small, {{"name", s.get("/api/maps/" + map).json()["name"]}, {"version", 2}}), "/api/maps/{id}",
             "patch", 409);
  }
  c.expectFile(s.get("/api/maps/" + map + "/layers/slope.png?max=256"), "/api/maps/{id}/layers/{file}", "get", 200, "image/png");
  c.expectFile(s.get("/api/maps/" + map + "/layers/elevation.tif"), "/api/maps/{id}/layers/{file}", "get", 200, "image/tiff");
  c.expect(s.get("/api/maps/" + map + "/layers/nope.png"), "/api/maps/{id}/layers/{file}", "get", 404);
  c.expect(s.get("/api/maps/" + map + "/layers/slope.png?max=x"), "/api/maps/{id}/layers/{file}", "get", 400);
  const std::string tiles = "/api/maps/{id}/tiles/{layer}/{z}/{x}/{y}";
  c.expectFile(s.get("/api/maps/" + map + "/tiles/hillshade/0/0/0.png"), tiles, "get", 200, "image/png");
  c.expectFile(s.get("/api/maps/" + map + "/tiles/elevation/2/1/0.f32"), tiles, "get", 200, "application/octet-stream");
  c.expect(s.get("/api/maps/" + map + "/tiles/slope/9/0/0.png"), tiles, "get", 404);
  c.expect(s.get("/api/maps/" + map + "/tiles/pdm/0/0/0.png"), tiles, "get", 400);
  const std::string upId = up["id"];
  c.expect(request(s.port(), "DELETE", "/api/maps/" + upId), "/api/maps/{id}", "delete", 200);
  c.expect(request(s.port(), "DELETE", "/api/maps/" + upId), "/api/maps/{id}", "delete", 404);

  // Keep-out zones: read, replace, refused.
  const json zones = {{"type", "FeatureCollection"},
                      {"features", {{{"type", "Feature"}, {"properties", {{"name", "rim"}}},
                                     {"geometry", {{"type", "Polygon"},
                                                   {"coordinates", {{{130, 10}, {140, 10}, {140, 20}, {130, 20}, {130, 10}}}}}}}}}};
  c.expect(send("PUT", "/api/maps/" + map + "/zones", zones), "/api/maps/{id}/zones", "put", 200);
  c.expect(send("PUT", "/api/maps/" + map + "/zones", {{"type", "Point"}}), "/api/maps/{id}/zones", "put", 400);
  c.expect(request(s.port(), "PUT", "/api/maps/" + map + "/zones", zones.dump(), "text/plain"), "/api/maps/{id}/zones", "put", 415);
  c.expect(s.get("/api/maps/" + map + "/zones"), "/api/maps/{id}/zones", "get", 200);
  c.expect(s.get("/api/maps/nope/zones"), "/api/maps/{id}/zones", "get", 404);
  const json empty = {{"type", "FeatureCollection"}, {"features", json::array()}};
  c.expect(send("PUT", "/api/maps/" + map + "/zones", empty), "/api/maps/{id}/zones", "put", 428);
  c.expect(request(s.port(), "PUT", "/api/maps/" + map + "/zones", empty.dump(), "application/json", {{"If-Match", "\"v0\""}}),
           "/api/maps/{id}/zones", "put", 412);
  c.expect(request(s.port(), "PUT", "/api/maps/" + map + "/zones", empty.dump(), "application/json", {{"If-Match", "\"v1\""}}),
           "/api/maps/{id}/zones", "put", 200);
  // One zone at a time (issue 26).
  const std::string zonesPath = "/api/maps/" + map + "/zones";
  const json zone = zones["features"][0];
  const std::string zoneId = c.expect(send("POST", zonesPath, zone), "/api/maps/{id}/zones", "post", 201)["id"];
  c.expect(send("POST", zonesPath, {{"type", "Point"}}), "/api/maps/{id}/zones", "post", 400);
  c.expect(s.get(zonesPath + "/" + zoneId), "/api/maps/{id}/zones/{zone}", "get", 200);
  c.expect(s.get(zonesPath + "/z999"), "/api/maps/{id}/zones/{zone}", "get", 404);
  const auto v1 = std::map<std::string, std::string>{{"If-Match", "\"v1\""}};
  c.expect(send("PUT", zonesPath + "/" + zoneId, zone), "/api/maps/{id}/zones/{zone}", "put", 428);
  c.expect(request(s.port(), "PUT", zonesPath + "/" + zoneId, zone.dump(), "application/json", v1),
           "/api/maps/{id}/zones/{zone}", "put", 200);
  c.expect(request(s.port(), "PUT", zonesPath + "/" + zoneId, zone.dump(), "application/json", v1),
           "/api/maps/{id}/zones/{zone}", "put", 412);
  c.expect(request(s.port(), "DELETE", zonesPath + "/" + zoneId, "", "", v1), "/api/maps/{id}/zones/{zone}", "delete", 412);
  c.expect(request(s.port(), "DELETE", zonesPath + "/" + zoneId, "", "", {{"If-Match", "x"}}), "/api/maps/{id}/zones/{zone}",
           "delete", 400);
  c.expect(request(s.port(), "DELETE", zonesPath + "/" + zoneId), "/api/maps/{id}/zones/{zone}", "delete", 428);
  c.expect(request(s.port(), "DELETE", zonesPath + "/" + zoneId, "", "", {{"If-Match", "\"v2\""}}),
           "/api/maps/{id}/zones/{zone}", "delete", 200);
  c.expect(request(s.port(), "DELETE", zonesPath + "/" + zoneId, "", "", v1), "/api/maps/{id}/zones/{zone}", "delete", 404);
  c.expect(s.get(zonesPath + "/history"), "/api/maps/{id}/zones/history", "get", 200);
  c.expect(s.get("/api/maps/nope/zones/history"), "/api/maps/{id}/zones/history", "get", 404);
  c.expect(s.get(zonesPath + "/history/1"), "/api/maps/{id}/zones/history/{version}", "get", 200);
  c.expect(s.get(zonesPath + "/history/99"), "/api/maps/{id}/zones/history/{version}", "get", 404);
  const long long zonesNow = s.get(zonesPath).json()["version"];
  c.expect(send("POST", zonesPath + "/restore", {{"restore", 1}, {"version", zonesNow}}), "/api/maps/{id}/zones/restore", "post", 200);
  c.expect(send("POST", zonesPath + "/restore", {{"restore", 1}, {"version", 1}}), "/api/maps/{id}/zones/restore", "post", 412);
  c.expect(send("POST", zonesPath + "/restore", {{"restore", 1}}), "/api/maps/{id}/zones/restore", "post", 428);
  c.expect(send("POST", zonesPath + "/restore", {{"version", 1}}), "/api/maps/{id}/zones/restore", "post", 400);
  // The event stream: its upgrade's refusals (test_events_api.cpp reads it).
  c.expectRefusedUpgrade("/api/events?since=-1", "/api/events", 400);
  c.expectRefusedUpgrade("/api/events?map=nope", "/api/events", 404);

  // PDMs.
  const json pdm = c.expect(s.postJson("/api/maps/" + map + "/pdms", {{"random", 2}, {"seed", 3}}), "/api/maps/{id}/pdms", "post", 201);
  c.expect(s.postJson("/api/maps/" + map + "/pdms", {{"random", 0}}), "/api/maps/{id}/pdms", "post", 400);
  c.expect(s.get("/api/maps/" + map + "/pdms"), "/api/maps/{id}/pdms", "get", 200);
  c.expect(s.get("/api/maps/nope/pdms"), "/api/maps/{id}/pdms", "get", 404);
  const std::string pdmPath = "/api/maps/" + map + "/pdms/" + pdm["id"].get<std::string>();
  c.expect(s.get(pdmPath), "/api/maps/{id}/pdms/{pdm}", "get", 200);
  c.expect(s.get("/api/maps/" + map + "/pdms/nope"), "/api/maps/{id}/pdms/{pdm}", "get", 404);
  const std::string onePdm = "/api/maps/{id}/pdms/{pdm}";
  c.expect(send("PUT", pdmPath, {{"name", "renamed"}}), onePdm, "put", 428);
  c.expect(send("PUT", pdmPath, {{"name", "renamed"}, {"version", 1}}), onePdm, "put", 200);
  c.expect(send("PUT", pdmPath, {{"name", "again"}, {"version", 1}}), onePdm, "put", 412);
  c.expect(send("PUT", pdmPath, {{"colour", "red"}, {"version", 2}}), onePdm, "put", 400);
  c.expect(send("PUT", "/api/maps/" + map + "/pdms/nope", {{"name", "x"}, {"version", 1}}), onePdm, "put", 404);
  c.expect(s.get(pdmPath + "/history"), "/api/maps/{id}/pdms/{pdm}/history", "get", 200);
  c.expect(s.get("/api/maps/" + map + "/pdms/nope/history"), "/api/maps/{id}/pdms/{pdm}/history", "get", 404);
  c.expect(s.get(pdmPath + "/history/1"), "/api/maps/{id}/pdms/{pdm}/history/{version}", "get", 200);
  c.expect(s.get(pdmPath + "/history/7"), "/api/maps/{id}/pdms/{pdm}/history/{version}", "get", 404);
  c.expect(send("POST", pdmPath + "/restore", {{"restore", 1}, {"version", 2}}), "/api/maps/{id}/pdms/{pdm}/restore", "post", 200);
  c.expect(send("POST", pdmPath + "/restore", {{"restore", 1}, {"version", 2}}), "/api/maps/{id}/pdms/{pdm}/restore", "post", 412);
  c.expect(send("POST", pdmPath + "/restore", {{"restore", 1}}), "/api/maps/{id}/pdms/{pdm}/restore", "post", 428);
  c.expect(send("POST", pdmPath + "/restore", {{"restore", 0}, {"version", 3}}), "/api/maps/{id}/pdms/{pdm}/restore", "post", 400);
  c.expect(send("POST", "/api/maps/" + map + "/pdms/nope/restore", {{"restore", 1}, {"version", 3}}),
           "/api/maps/{id}/pdms/{pdm}/restore", "post", 404);
  c.expect(request(s.port(), "DELETE", pdmPath, "", "", {{"If-Match", "\"v1\""}}), onePdm, "delete", 412);
  c.expect(request(s.port(), "DELETE", pdmPath), "/api/maps/{id}/pdms/{pdm}", "delete", 200);
  c.expect(request(s.port(), "DELETE", pdmPath), "/api/maps/{id}/pdms/{pdm}", "delete", 404);

  // Missions: launch, refusals, the run, its files, its stream refused, its deletion.
  const json mission = {{"map", map}, {"planner", "coverage"}, {"pace", 0},
                        {"rovers", {{{"x", 20}, {"y", 20}, {"heading", 0}}}}, {"params", {{"coverage", 0.05}}}};
  const std::string id = c.expect(s.postJson("/api/missions", mission), "/api/missions", "post", 202)["id"];
  c.expect(s.postJson("/api/missions", {{"map", map}}), "/api/missions", "post", 400);
  c.expect(request(s.port(), "POST", "/api/missions", mission.dump(), "text/plain"), "/api/missions", "post", 415);
  s.waitFinished(id);
  c.expect(s.get("/api/missions"), "/api/missions", "get", 200);
  c.expect(s.get("/api/missions?offset=-1"), "/api/missions", "get", 400);
  c.expect(s.get("/api/missions/" + id), "/api/missions/{id}", "get", 200);
  c.expect(s.get("/api/missions/nope"), "/api/missions/{id}", "get", 404);
  c.expect(send("PATCH", "/api/missions/" + id, {{"label", "strip B"}}), "/api/missions/{id}", "patch", 428);
  c.expect(send("PATCH", "/api/missions/" + id, {{"label", "strip B"}, {"version", 1}}), "/api/missions/{id}", "patch", 200);
  c.expect(send("PATCH", "/api/missions/" + id, {{"label", "strip C"}, {"version", 1}}), "/api/missions/{id}", "patch", 412);
  c.expect(send("PATCH", "/api/missions/" + id, {{"colour", "red"}}), "/api/missions/{id}", "patch", 400);
  const std::string files = "/api/missions/{id}/{file}";
  c.expect(s.get("/api/missions/" + id + "/mission.json"), files, "get", 200);
  c.expect(s.get("/api/missions/" + id + "/result.json"), files, "get", 200);
  c.expectFile(s.get("/api/missions/" + id + "/result.csv"), files, "get", 200, "text/csv");
  c.expectFile(s.get("/api/missions/" + id + "/result.geojson"), files, "get", 200, "application/geo+json");
  c.expectFile(s.get("/api/missions/" + id + "/map.png"), files, "get", 200, "image/png");
  c.expectFile(s.get("/api/missions/" + id + "/replay.mcap"), files, "get", 200, "application/octet-stream");
  c.expect(s.get("/api/missions/" + id + "/nope.txt"), files, "get", 404);
  c.expectRefusedUpgrade("/api/missions/nope/stream", "/api/missions/{id}/stream", 404);
  c.expect(request(s.port(), "DELETE", "/api/missions/" + id), "/api/missions/{id}", "delete", 200);
  c.expect(request(s.port(), "DELETE", "/api/missions/" + id), "/api/missions/{id}", "delete", 404);

  // Studies: presets, a tiny study to its end, its downloads and runs, refusals, its deletion.
  c.expect(s.get("/api/studies/presets"), "/api/studies/presets", "get", 200);
  const json tiny = {{"name", "tiny"}, {"planner", "coverage"}, {"runs", 2},
                     {"worlds", {{{"name", "20x20"}, {"grid", {{"rows", 20}, {"cols", 20}}}}}}, {"levels", {0.9}}};
  const std::string study = c.expect(s.postJson("/api/studies", tiny), "/api/studies", "post", 202)["id"];
  c.expect(s.postJson("/api/studies", {{"planner", "nope"}}), "/api/studies", "post", 400);
  rover::test::waitUntil(
      [&] { return s.get("/api/studies/" + study).json()["status"] == "succeeded"; }, rover::test::kHangDeadline,
      "the study to succeed");
  c.expect(s.get("/api/studies"), "/api/studies", "get", 200);
  c.expect(s.get("/api/studies/" + study), "/api/studies/{id}", "get", 200);
  c.expect(s.get("/api/studies/nope"), "/api/studies/{id}", "get", 404);
  c.expect(send("PATCH", "/api/studies/" + study, {{"name", "tiny east"}}), "/api/studies/{id}", "patch", 428);
  c.expect(send("PATCH", "/api/studies/" + study, {{"name", "tiny east"}, {"version", 1}}), "/api/studies/{id}", "patch", 200);
  c.expect(send("PATCH", "/api/studies/" + study, {{"name", "tiny west"}, {"version", 1}}), "/api/studies/{id}", "patch", 412);
  c.expect(send("PATCH", "/api/studies/" + study, {{"name", 3}, {"version", 2}}), "/api/studies/{id}", "patch", 400);
  c.expect(send("PATCH", "/api/studies/nope", {{"name", "x"}, {"version", 1}}), "/api/studies/{id}", "patch", 404);
  c.expectFile(s.get("/api/studies/" + study + "/runs.csv"), "/api/studies/{id}/runs.csv", "get", 200, "text/csv");
  c.expect(s.get("/api/studies/nope/runs.csv"), "/api/studies/{id}/runs.csv", "get", 404);
  c.expectFile(s.get("/api/studies/" + study + "/study.sqlite"), "/api/studies/{id}/study.sqlite", "get", 200,
               "application/vnd.sqlite3");
  c.expect(s.get("/api/studies/nope/study.sqlite"), "/api/studies/{id}/study.sqlite", "get", 404);
  c.expectFile(s.get("/api/studies/" + study + "/benchmark.db"), "/api/studies/{id}/benchmark.db", "get", 200,
               "application/vnd.sqlite3");
  c.expect(s.get("/api/studies/nope/benchmark.db"), "/api/studies/{id}/benchmark.db", "get", 404);
  c.expect(s.get("/api/studies/" + study + "/runs/1"), "/api/studies/{id}/runs/{run}", "get", 200);
  c.expect(s.get("/api/studies/" + study + "/runs/2"), "/api/studies/{id}/runs/{run}", "get", 404);
  c.expect(s.post("/api/studies/" + study + "/runs/0/mission", ""), "/api/studies/{id}/runs/{run}/mission", "post", 409);
  c.expect(s.post("/api/studies/nope/runs/0/mission", ""), "/api/studies/{id}/runs/{run}/mission", "post", 404);
  c.expectRefusedUpgrade("/api/studies/nope/stream", "/api/studies/{id}/stream", 404);
  c.expect(request(s.port(), "DELETE", "/api/studies/" + study), "/api/studies/{id}", "delete", 200);
  c.expect(request(s.port(), "DELETE", "/api/studies/" + study), "/api/studies/{id}", "delete", 404);

  // Every route was answered and checked.
  for (const auto& r : s.router.routes()) {
    std::string method = r.method == "WS" ? "ws" : r.method;
    std::transform(method.begin(), method.end(), method.begin(), [](unsigned char ch) { return std::tolower(ch); });
    CHECK_MESSAGE(c.answered.count(method + " " + r.pattern), r.method << " " << r.pattern << " was not checked");
  }
}
