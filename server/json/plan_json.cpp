#include "server/json/plan_json.hpp"

#include <cmath>
#include <cstdint>

#include "core/common/error.hpp"

namespace rover::json {

using nlohmann::json;

json toJson(const ParamValue& v) {
  return std::visit([](const auto& x) { return json(x); }, v);
}

json toJson(const ParamInfo& info) {
  json j{{"key", info.key},
         {"type", paramTypeName(info.type)},
         {"default", toJson(info.defaultValue)},
         {"unit", info.unit},
         {"doc", info.doc}};
  if (std::isfinite(info.min)) j["min"] = info.min;
  if (std::isfinite(info.max)) j["max"] = info.max;
  if (!info.choices.empty()) j["choices"] = info.choices;
  j["group"] = info.group;
  j["level"] = paramLevelName(info.level);
  return j;
}

json toJson(const ParamSet& values) {
  json j = json::object();
  for (const auto& [key, value] : values) j[key] = toJson(value);
  return j;
}

json toJson(const std::vector<ParamPreset>& presets) {
  json arr = json::array();
  for (const auto& p : presets) arr.push_back({{"name", p.name}, {"doc", p.doc}, {"params", toJson(p.values)}});
  return arr;
}

json toJson(const std::vector<ParamInfo>& infos) {
  json arr = json::array();
  for (const auto& i : infos) arr.push_back(toJson(i));
  return arr;
}

namespace {
json metricsObject(const std::vector<Metric>& metrics) {
  json m = json::object();
  for (const auto& x : metrics) m[x.key] = x.value;
  return m;
}
}  // namespace

json toJson(const Incident& i) {
  json x{{"kind", enumName(i.kind)}, {"rover", i.rover}, {"time_s", i.time},
         {"x", i.position.x()}, {"y", i.position.y()}, {"note", i.note}};
  if (i.other >= 0) x["other"] = i.other;
  if (i.step >= 0) x["step"] = i.step;
  if (!i.cause.empty()) x["cause"] = i.cause;
  if (i.kind == IncidentKind::Collision) x["distance_m"] = i.value;
  else if (i.kind == IncidentKind::Exceedance) x["max_angle_deg"] = i.value;
  else if (i.kind == IncidentKind::Bump) x["cell"] = static_cast<int>(i.value);
  else if (i.value >= 0) x["target"] = static_cast<int>(i.value);
  return x;
}

json toJson(const PlanResult& r) {
  json j{{"planner", r.planner},
         {"stop_reason", enumName(r.stopReason)},
         {"cancelled", r.cancelled},
         {"metrics", metricsObject(r.metrics)}};
  json units = json::object();
  for (const auto& m : r.metrics)
    if (!m.unit.empty()) units[m.key] = m.unit;
  j["metric_units"] = units;
  json rovers = json::array();
  for (const auto& t : r.tracks) {
    json path = json::array();
    for (const auto& p : t.points) path.push_back({p.x(), p.y()});
    json rover{{"rover", t.rover}, {"metrics", metricsObject(t.metrics)}, {"path", path}};
    if (!t.believed.empty()) {
      json believed = json::array();
      for (const auto& p : t.believed) believed.push_back({p.x(), p.y()});
      rover["believed_path"] = std::move(believed);
    }
    rovers.push_back(std::move(rover));
  }
  j["rovers"] = rovers;
  json series = json::object();
  for (const auto& s : r.series)
    series[s.key] = {{"x_label", s.xLabel}, {"y_label", s.yLabel}, {"x", s.x}, {"y", s.y}};
  j["series"] = series;
  if (!r.overlays.empty()) {
    json overlays = json::array();
    for (const auto& o : r.overlays) {
      json pts = json::array();
      for (const auto& p : o.points) pts.push_back({p.x(), p.y()});
      overlays.push_back({{"key", o.key}, {"rover", o.rover}, {"points", pts}});
    }
    j["overlays"] = overlays;
  }
  j["warnings"] = r.warnings;  // empty: completed cleanly
  if (!r.assumptions.empty()) {
    json a = json::object();
    for (const auto& [k, v] : r.assumptions) a[k] = v;
    j["assumptions"] = a;
  }
  json incidents = json::array();
  for (const auto& i : r.incidents) incidents.push_back(toJson(i));
  j["incidents"] = incidents;
  if (!r.targets.empty()) {
    json targets = json::array();
    for (const auto& t : r.targets)
      targets.push_back({{"target", t.index}, {"x", t.position.x()}, {"y", t.position.y()},
                         {"status", enumName(t.status)}, {"legs_reached", t.reached}, {"legs_short", t.shortLegs},
                         {"legs_skipped", t.skipped}, {"legs_no_slot", t.noSlot}});
    j["targets"] = std::move(targets);
  }
  return j;
}

ParamValue paramFromJson(const ParamInfo& info, const json& v) {
  switch (info.type) {
    case ParamType::Bool:
      if (!v.is_boolean()) throwInvalidParameter(info.key, "expected true or false");
      return v.get<bool>();
    case ParamType::Int:
      if (v.is_number_unsigned() && v.get<std::uint64_t>() > INT64_MAX)
        throwInvalidParameter(info.key, "is out of range");
      if (v.is_number_integer()) return v.get<std::int64_t>();
      if (v.is_number_float()) return v.get<double>();  // 3.0 is accepted, 3.5 rejected later
      throwInvalidParameter(info.key, "expected an integer");
    case ParamType::Real:
      if (v.is_number_unsigned()) return static_cast<double>(v.get<std::uint64_t>());
      if (v.is_number_integer()) return v.get<std::int64_t>();
      if (v.is_number_float()) return v.get<double>();
      throwInvalidParameter(info.key, "expected a number");
    case ParamType::Choice:
      if (!v.is_string()) throwInvalidParameter(info.key, "expected a string");
      return v.get<std::string>();
    case ParamType::RealList: {
      if (!v.is_array()) throwInvalidParameter(info.key, "expected an array of numbers");
      std::vector<double> out;
      for (const auto& x : v) {
        if (!x.is_number()) throwInvalidParameter(info.key, "expected an array of numbers");
        out.push_back(x.get<double>());
      }
      return out;
    }
  }
  throwInvalidParameter(info.key, "unsupported parameter type");
}

}  // namespace rover::json
