#include "server/json/planner_json.hpp"

#include "server/json/plan_json.hpp"

namespace rover::json {

using nlohmann::json;

std::string groundName(Ground g) {
  switch (g) {
    case Ground::CoverageGrid: return "coverage_grid";
    case Ground::DemAndPdm: return "dem_pdm";
  }
  return "coverage_grid";
}

std::string startPlacementName(StartPlacement s) {
  switch (s) {
    case StartPlacement::RandomCells: return "random";
    case StartPlacement::Formation: return "formation";
  }
  return "random";
}

std::string progressName(ProgressMeasure p) {
  switch (p) {
    case ProgressMeasure::Coverage: return "coverage";
    case ProgressMeasure::Detection: return "detection";
  }
  return "coverage";
}

std::vector<std::string> groundNames() { return {groundName(Ground::CoverageGrid), groundName(Ground::DemAndPdm)}; }
std::vector<std::string> startPlacementNames() {
  return {startPlacementName(StartPlacement::RandomCells), startPlacementName(StartPlacement::Formation)};
}
std::vector<std::string> progressNames() {
  return {progressName(ProgressMeasure::Coverage), progressName(ProgressMeasure::Detection)};
}

json toJson(const PlannerSpecs& specs) {
  json metrics = json::array();
  for (const auto& m : specs.metrics) metrics.push_back({{"key", m.key}, {"unit", m.unit}, {"doc", m.doc}});
  json stages = json::array();
  for (const auto& s : specs.stages) stages.push_back({{"name", s.name}, {"doc", s.doc}});
  return {{"ground", groundName(specs.ground)},
          {"starts", startPlacementName(specs.starts)},
          {"progress", {{"measure", progressName(specs.progress)}, {"series", specs.progressSeries}}},
          {"seconds_per_run", specs.secondsPerRun},
          {"metrics", std::move(metrics)},
          {"stages", std::move(stages)}};
}

json plannerJson(const Planner& planner, const json& mapInfo, const ParamSet& mapDefaults) {
  json params = toJson(planner.params());
  json defaults = mapInfo;
  for (auto& info : params)
    if (auto d = mapDefaults.find(info["key"].get<std::string>()); d != mapDefaults.end())
      info["default"] = defaults[d->first] = toJson(d->second);
  json entry{{"name", planner.name()}, {"summary", planner.summary()}, {"params", params},
             {"presets", toJson(planner.presets())}};
  if (!mapInfo.is_null()) entry["map_defaults"] = defaults;
  entry.update(toJson(planner.specs()));
  return entry;
}

}  // namespace rover::json
