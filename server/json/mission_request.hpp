#pragma once
// A mission request read from its JSON body into a typed struct (DESIGN.md: "validated at the edge
// into a typed struct"). Pure: it sees the planner registry's parameter tables, never the database
// or a map, so a fuzzer can drive it. What needs the map (rovers inside it, the PDM's map) is
// checked afterwards by the route and the planner's own validate().
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/planning/mission_area.hpp"
#include "core/planning/planner.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::json {

struct MissionRequest {
  std::string mapId;
  std::string pdmId;  // "" when none
  std::string planner;
  std::string name;   // "" when none
  ParamSet params;    // every value typed and inside its table range
  std::vector<RoverStart> rovers;  // local metres; heading in radians
  std::optional<double> pace;      // steps per second
  nlohmann::json spec;             // the body as accepted, without map, pdm and planner
  // From a mission file (server/api/mission_file.hpp): the grid digest its map must have.
  std::optional<std::string> demSha256;
  // `keep_out`: a FeatureCollection of Polygons in the local frame (zones_json.hpp); checked
  // against the map's extent by the route, which knows the map.
  KeepOut keepOut;
  // `area` (optional, null = none): the mission area (server/json/area_json.hpp), checked against
  // the map by the service.
  std::optional<MissionArea> area;
};

// Limits stated in README (API): at most kMaxRovers rovers; x and y finite with |v| <= 1e9 m (the
// planner then checks they lie on the map); heading in [-360, 360] degrees; pace in [0, 1e6].
inline constexpr std::size_t kMaxRovers = planning::kMaxRovers;
inline constexpr double kMaxCoordinateM = 1e9;
inline constexpr double kMaxHeadingDeg = 360;
inline constexpr double kMaxPace = 1e6;
// Every top-level field a request (or a mission file) may hold; any other is 400 unknown_field.
inline constexpr const char* kMissionRequestFields[] = {"map",     "pdm",       "planner",    "rovers",
                                                        "params",  "pace",      "name",       "format",
                                                        "version", "roverplan", "dem_sha256", "map_name",
                                                        "keep_out", "area",     "used"};

// A mission file's own fields are accepted too: format ("roverplan-mission"), version (at most
// `maxFileVersion`), dem_sha256 (64 hex digits, or null) and the informative roverplan and
// map_name (strings, not checked further).
// `keep_out` (optional, null = none): keep-out zones, GeoJSON FeatureCollection of Polygons in the
// local frame (server/json/zones_json.hpp for its limits).
// Throws http::ApiError (400) naming the field: "map", "planner", "params.KEY", "rovers[2].x",
// "keep_out.features[0].geometry.coordinates", ...
MissionRequest parseMissionRequest(const nlohmann::json& body, const PlannerRegistry& planners,
                                   int maxFileVersion = 1);

}  // namespace rover::json
