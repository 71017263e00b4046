#include "server/json/mission_request.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/error.hpp"
#include "server/http/http_types.hpp"
#include "server/json/area_json.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/plan_json.hpp"
#include "server/json/zones_json.hpp"

namespace rover::json {

using http::ApiError;
using nlohmann::json;

namespace {

std::string stringField(const json& body, const char* key, bool required) {
  auto it = body.find(key);
  if (it == body.end() || it->is_null()) {
    if (required) throw ApiError(400, "missing_field", std::string(key) + " is required", key);
    return "";
  }
  if (!it->is_string()) throw ApiError(400, "invalid_field", std::string(key) + " must be a string", key);
  std::string value = it->get<std::string>();
  checkName(value, key);
  return value;
}

// A finite number in [lo, hi], or 400 naming `field`.
double boundedNumber(const json& v, const std::string& field, double lo, double hi, const std::string& what) {
  if (!v.is_number()) throw ApiError(400, "invalid_field", field + " must be " + what, field);
  const double d = v.get<double>();
  if (!std::isfinite(d) || d < lo || d > hi) throw ApiError(400, "invalid_field", field + " must be " + what, field);
  return d;
}

// Typed by the table, then checked against its range / choices, so an absurd value is refused
// here with its field rather than deep inside a planner.
ParamValue paramValue(const ParamInfo& info, const json& value) {
  ParamValue v = paramFromJson(info, value);
  switch (info.type) {
    case ParamType::Bool:
      paramAsBool(info.key, v);
      break;
    case ParamType::Int:
      paramAsInt(info, v);
      break;
    case ParamType::Real:
      paramAsReal(info, v);
      break;
    case ParamType::Choice:
      paramAsChoice(info, v);
      break;
    case ParamType::RealList:
      paramAsRealList(info.key, v);
      break;
  }
  return v;
}

}  // namespace

MissionRequest parseMissionRequest(const json& body, const PlannerRegistry& planners,
                                   int maxFileVersion) {
  if (!body.is_object()) throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  for (const auto& item : body.items())
    if (std::find(std::begin(kMissionRequestFields), std::end(kMissionRequestFields), item.key()) ==
        std::end(kMissionRequestFields))
      throw ApiError(400, "unknown_field", "unknown field '" + shown(item.key()) + "'", shown(item.key()));
  MissionRequest req;
  req.mapId = stringField(body, "map", true);
  req.pdmId = stringField(body, "pdm", false);
  req.planner = stringField(body, "planner", true);
  req.name = stringField(body, "name", false);
  const Planner* planner = nullptr;
  try {
    planner = &planners.get(req.planner);
  } catch (const Error& e) {
    throw ApiError(400, "unknown_planner", e.what(), "planner");
  }

  // Parameters: typed by the planner's own table; unknown keys rejected.
  if (auto params = body.find("params"); params != body.end() && !params->is_null()) {
    if (!params->is_object()) throw ApiError(400, "invalid_field", "params must be an object", "params");
    const auto infos = planner->params();
    for (const auto& item : params->items()) {
      // Not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
      const std::string& key = item.key();
      auto info = std::find_if(infos.begin(), infos.end(), [&](const ParamInfo& i) { return i.key == key; });
      if (info == infos.end())
        throw ApiError(400, "unknown_parameter",
                       "unknown parameter '" + shown(key) + "' for planner " + req.planner,
                       "params." + shown(key));
      try {
        req.params[key] = paramValue(*info, item.value());
      } catch (const Error& e) {
        throw ApiError(400, errorCodeName(e.code()), e.what(), "params." + key);
      }
    }
  }

  // Rovers in the local frame (metres from the lower-left corner), heading in degrees.
  auto rovers = body.find("rovers");
  if (rovers == body.end() || !rovers->is_array() || rovers->empty() || rovers->size() > kMaxRovers)
    throw ApiError(400, "invalid_field",
                   "rovers must be an array of 1 to " + std::to_string(kMaxRovers) + " {x, y, heading}", "rovers");
  for (std::size_t k = 0; k < rovers->size(); ++k) {
    const json& r = (*rovers)[k];
    const std::string f = "rovers[" + std::to_string(k) + "]";
    if (!r.is_object()) throw ApiError(400, "invalid_field", f + " must be an object {x, y, heading}", f);
    for (const char* key : {"x", "y"})
      if (!r.contains(key))
        throw ApiError(400, "invalid_field", f + "." + key + " must be a number", f + "." + key);
    const std::string coord = "a finite number of metres with |value| <= 1e9";
    const double x = boundedNumber(r["x"], f + ".x", -kMaxCoordinateM, kMaxCoordinateM, coord);
    const double y = boundedNumber(r["y"], f + ".y", -kMaxCoordinateM, kMaxCoordinateM, coord);
    double heading = 0;
    if (r.contains("heading") && !r["heading"].is_null())
      heading = boundedNumber(r["heading"], f + ".heading", -kMaxHeadingDeg, kMaxHeadingDeg,
                              "a number of degrees in [-360, 360]");
    req.rovers.push_back({{x, y}, heading * std::numbers::pi / 180.0});
  }
  if (auto k = body.find("keep_out"); k != body.end() && !k->is_null())
    req.keepOut = zonesFromJson(*k, "keep_out");
  if (auto a = body.find("area"); a != body.end() && !a->is_null()) req.area = areaFromJson(*a, "area");
  if (auto pace = body.find("pace"); pace != body.end())
    req.pace = boundedNumber(*pace, "pace", 0, kMaxPace, "a number of steps per second in [0, 1e6]");

  // A mission file's own fields.
  if (body.contains("format")) {
    if (stringField(body, "format", false) != "roverplan-mission")
      throw ApiError(400, "invalid_field", "format must be \"roverplan-mission\"", "format");
  }
  if (auto v = body.find("version"); v != body.end()) {
    if (!v->is_number_integer() || v->get<long long>() < 1)
      throw ApiError(400, "invalid_field", "version must be a whole number from 1", "version");
    if (v->get<long long>() > maxFileVersion)
      throw ApiError(400, "unsupported_version",
                     "mission file version " + std::to_string(v->get<long long>()) +
                         " is newer than this server reads (" + std::to_string(maxFileVersion) + ")",
                     "version");
  }
  stringField(body, "roverplan", false);
  stringField(body, "map_name", false);
  if (auto d = body.find("dem_sha256"); d != body.end() && !d->is_null()) {
    const bool hex = d->is_string() && d->get<std::string>().size() == 64 &&
                     d->get<std::string>().find_first_not_of("0123456789abcdef") == std::string::npos;
    if (!hex) throw ApiError(400, "invalid_field", "dem_sha256 must be 64 lower-case hex digits", "dem_sha256");
    req.demSha256 = d->get<std::string>();
  }

  req.spec = body;
  // "used" (the versions a run used, issue 26) is the server's to write: informative in a file.
  for (const char* key : {"map", "pdm", "planner", "format", "version", "roverplan", "dem_sha256", "map_name", "used"})
    req.spec.erase(key);
  return req;
}

}  // namespace rover::json
