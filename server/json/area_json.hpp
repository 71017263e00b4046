#pragma once
// A mission area at the JSON edge (issue 24; core/planning/mission_area.hpp): a mission request's
// or mission file's `area`, and the `area` and `planning_window` of a result.
//   {"bbox": [x0, y0, x1, y1]}           a rectangle, metres in the map's local frame
//   {"polygon": [[x, y], [x, y], ...]}   one ring of 3 to 1024 vertices (closing vertex optional)
// Errors are http::ApiError 400 naming the field ("area", "area.bbox", "area.polygon[3]"). The
// checks that need the map (on it, not degenerate, its window small enough) are core's
// checkMissionArea, which the service runs with the map's grid.
#include <string>

#include <nlohmann/json.hpp>

#include "core/planning/mission_area.hpp"

namespace rover::json {

MissionArea areaFromJson(const nlohmann::json& value, const std::string& field = "area");
nlohmann::json areaToJson(const MissionArea& area);
// {"origin": [x, y] (the window's lower-left corner, map frame, m), "row0", "col0" (its first
// cell on the map, row 0 north), "rows", "cols", "cell_size_m"}.
nlohmann::json windowToJson(const PlanningWindow& window);

}  // namespace rover::json
