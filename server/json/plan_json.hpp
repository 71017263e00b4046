#pragma once
// JSON at the edge (DESIGN.md): planner results, parameter descriptions and values as JSON, for the
// CLI's --json output and the REST API.
#include <nlohmann/json.hpp>

#include "core/common/params.hpp"
#include "core/planning/plan_result.hpp"

namespace rover::json {

nlohmann::json toJson(const ParamValue& v);
nlohmann::json toJson(const ParamInfo& info);
nlohmann::json toJson(const std::vector<ParamInfo>& infos);
nlohmann::json toJson(const ParamSet& values);
nlohmann::json toJson(const std::vector<ParamPreset>& presets);
nlohmann::json toJson(const PlanResult& r);
// One incident as result.json's `incidents` and the live stream's incident frames hold it.
nlohmann::json toJson(const Incident& i);
// Reads a JSON value as a parameter of the declared type; throws rover::Error naming the key.
ParamValue paramFromJson(const ParamInfo& info, const nlohmann::json& v);

}  // namespace rover::json
