#pragma once
// A planner's description (core/planning/planner_specs.hpp) at the JSON edge: the one place its
// enums get their names, for GET /api/planners, OpenAPI's enums and study documents.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/planning/planner.hpp"

namespace rover::json {

// "coverage_grid" | "dem_pdm".
std::string groundName(Ground g);
// "random" | "formation" (a study document's `starts`).
std::string startPlacementName(StartPlacement s);
// "coverage" | "detection".
std::string progressName(ProgressMeasure p);

// Every name of each enum, for OpenAPI.
std::vector<std::string> groundNames();
std::vector<std::string> startPlacementNames();
std::vector<std::string> progressNames();

// {ground, starts, progress: {measure, series}, seconds_per_run, metrics: [{key, unit, doc}],
//  stages: [{name, doc}]}: the members GET /api/planners adds to a planner's entry.
nlohmann::json toJson(const PlannerSpecs& specs);

// A planner's entry of GET /api/planners: name, summary, params, presets and its description;
// with a map (`mapInfo` {map, body} not null) the defaults that come from it filled in and listed
// in map_defaults.
nlohmann::json plannerJson(const Planner& planner, const nlohmann::json& mapInfo = nullptr,
                           const ParamSet& mapDefaults = {});

}  // namespace rover::json
