#pragma once
// The mission service of the API: a launch request (POST /api/missions, a mission file, a study
// run opened as a mission) built into a validated problem, admitted against the memory and disk
// budgets, and queued. The routes only parse and answer.
#include <nlohmann/json.hpp>

#include "server/api/routes.hpp"
#include "server/missions/mission_manager.hpp"

namespace rover::api {

// The mission a request describes, validated (every error names its field: 400, 404 not_found
// for the map or PDM, 409 map_changed for a mission file of another grid, 507 when the map's disk
// budget is full) and admitted (413 / 429 before anything big is built). The problem is built
// once to validate and dropped: a queued mission holds only its request, and a worker builds it
// again when it starts the mission (MissionJob::build).
missions::MissionJob buildMission(ApiContext& ctx, const nlohmann::json& request);

// buildMission, then queued under a new id: the stored record, status "queued".
// `by`: the operator, for the "created" event (issue 26).
store::MissionRecord submitMission(ApiContext& ctx, const nlohmann::json& request, const std::string& by = "");

}  // namespace rover::api
