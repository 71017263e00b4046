// The OpenAPI document is a contract a client can be generated from (issue 13): it is
// structurally valid 3.0.3, every $ref resolves, every route declares the statuses it answers,
// and the answers of the main routes match the schemas the document gives for them (a small
// JSON-schema subset validator below: type, nullable, enum, properties, required,
// additionalProperties, items, minItems/maxItems, minimum/maximum, maxLength, pattern,
// anyOf/oneOf, $ref).
#include <doctest/doctest.h>

#include <regex>
#include <set>

#include "api_server.hpp"
#include "server/json/mission_request.hpp"

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
  // Checks an answer's status is documented for the route and its body matches the schema.
  json expect(const rover::test::HttpResult& r, const std::string& pattern, const std::string& method, int status) {
    CHECK_MESSAGE(r.status == status, method << " " << pattern << ": " << r.status << " " << r.body.substr(0, 300));
    const json body = r.json();
    const auto problems = checker.check(body, responseSchema(doc, pattern, method, r.status));
    CHECK_MESSAGE(problems.empty(), method << " " << pattern << " " << r.status << ": " << (problems.empty() ? "" : problems[0]));
    return body;
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
  for (const auto& [path, item] : doc["paths"].items()) {
    CHECK(path.rfind("/api/", 0) == 0);
    for (const auto& [method, op] : item.items()) {
      CHECK_MESSAGE(methods.count(method), path << " " << method);
      REQUIRE(op.contains("responses"));
      CHECK(!op["responses"].empty());
      const std::string id = op["operationId"];
      CHECK_MESSAGE(operationIds.insert(id).second, "operationId " << id << " is used twice");
      for (const auto& [status, resp] : op["responses"].items()) {
        CHECK_MESSAGE(std::regex_match(status, statusRe), path << " " << status);
        CHECK(resp["description"].is_string());
        // Every error answers the Error schema.
        if (status[0] == '4' || status[0] == '5')
          CHECK(resp["content"]["application/json"]["schema"]["$ref"] == "#/components/schemas/Error");
      }
      // Path parameters declared, once each, required.
      std::set<std::string> declared;
      for (const auto& p : op.value("parameters", json::array())) {
        CHECK(p["schema"].is_object());
        CHECK((p["in"] == "path" || p["in"] == "query"));
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
  CHECK(doc["paths"]["/api/missions/{id}/stream"]["get"]["responses"].contains("101"));
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
  c.expect(request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":"strip A"})", "application/json"),
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
