#pragma once
// A mission file (issue 13, GET /api/missions/{id}/mission.json): everything needed to run a
// mission again — its map (id and the SHA-256 of the grid it was launched on, recorded with the
// run at launch; maps/dem_digest), PDM, planner, rovers, the
// parameters as they were given (the rest take the planner's defaults of the version named in
// the file, seed included), pace, name, keep-out zones and mission area. POST /api/missions
// takes it back as it is: the request fields are the same, and the file's own fields are checked
// (format, version, and the map's digest, so a re-run never silently plans on other ground).
#include <string>

#include <nlohmann/json.hpp>

#include "server/store/database.hpp"

namespace rover::api {

inline constexpr const char* kMissionFileFormat = "roverplan-mission";
inline constexpr int kMissionFileVersion = 1;

// `demSha256` is the digest of the mission's map ("" when the map is gone: the field is null and
// the file can only be re-run once the same DEM is uploaded and the map id edited).
nlohmann::json missionFile(const store::MissionRecord& m, const std::string& demSha256,
                           const std::string& version);

}  // namespace rover::api
