// The OpenAPI document's component schemas (GET /api/openapi.json, server/api/openapi.cpp): the
// error, the resources the routes answer with, the mission request and each planner's
// parameters, built from the same tables the validation reads.
#include "server/api/openapi.hpp"

#include <algorithm>
#include <cmath>

#include "core/pdm/pdm.hpp"
#include "core/planning/mission_area.hpp"
#include "maps/dem_import_options.hpp"
#include "server/api/mission_file.hpp"
#include "server/api/openapi_kit.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/plan_json.hpp"
#include "server/json/planner_json.hpp"
#include "server/json/zones_json.hpp"
#include "server/store/run_status.hpp"

namespace rover::api::openapi {

using nlohmann::json;
using namespace kit;

namespace {

// Component name of a planner's parameters: "Params_coverage", "Params_team-search".
std::string paramsComponent(const std::string& planner) { return "Params_" + planner; }

json paramInfoSchema() {
  return object({{"key", str()},
                 {"type", {{"type", "string"}, {"enum", {"bool", "int", "real", "choice", "real_list"}}}},
                 {"default", json::object()},
                 {"unit", str()},
                 {"doc", str()},
                 {"min", num()},
                 {"max", num()},
                 {"choices", {{"type", "array"}, {"items", str()}}},
                 {"group", str("The form's section (route, RRT*, coordination, rover, simulation, ...).")},
                 {"level", {{"type", "string"}, {"enum", {"common", "advanced"}}}}},
                {"key", "type", "default", "unit", "doc", "group", "level"});
}

// A plan's result.json as server/json/plan_json.cpp writes it (the outcome fields in full).
json planResultSchema() {
  json incident = object({{"kind", oneOf<IncidentKind>()},
                          {"rover", {{"type", "integer"}}},
                          {"other", {{"type", "integer"}}},
                          {"time_s", num()},
                          {"step", {{"type", "integer"}}},
                          {"x", num("Metres, local frame.")},
                          {"y", num("Metres, local frame.")},
                          {"note", str("What happened, with the limit hit (parameter name and value) and the value reached.")},
                          {"cause", str("Why, as a short name incidents are grouped by: the limit hit (exceedance_limit, safety_distance), "
                                        "a leg's reason (steep, no_path, conflict, pieces_exhausted, keep_out, invalid_goal), "
                                        "no_ground (no_slot), off_field or unmapped_obstacle (bump).")},
                          {"distance_m", num("collision: the closest distance.")},
                          {"max_angle_deg", num("exceedance: the worst |roll| or |pitch|.")},
                          {"cell", {{"type", "integer"}, {"description", "bump: the cell driven into."}}},
                          {"target", {{"type", "integer"}, {"description", "short, skipped, no_slot: the route target."}}}},
                         {"kind", "rover", "x", "y", "note"});
  json target = object({{"target", {{"type", "integer"}}},
                        {"x", num()},
                        {"y", num()},
                        {"status", oneOf<TargetStatus>()},
                        {"legs_reached", {{"type", "integer"}}},
                        {"legs_short", {{"type", "integer"}}},
                        {"legs_skipped", {{"type", "integer"}}},
                        {"legs_no_slot", {{"type", "integer"}}}},
                       {"target", "x", "y", "status"});
  return object({{"planner", str()},
                 {"stop_reason", oneOf<StopReason>()},
                 {"cancelled", {{"type", "boolean"}}},
                 {"metrics", {{"type", "object"}, {"additionalProperties", num()}}},
                 {"metric_units", {{"type", "object"}, {"additionalProperties", str()}}},
                 {"rovers", {{"type", "array"}, {"items", {{"type", "object"}}}}},
                 {"series", {{"type", "object"}}},
                 {"warnings", {{"type", "array"}, {"items", str()}}},
                 {"incidents", {{"type", "array"}, {"items", incident}}},
                 {"targets", {{"type", "array"}, {"items", target}}},
                 {"area", {{"type", "object"}, {"allOf", {openapi::ref("MissionArea")}}, {"nullable", true},
                           {"description", "The mission's area as asked; null: the whole map."}}},
                 {"planning_window", openapi::ref("PlanningWindow")}},
                {"planner", "stop_reason", "cancelled", "metrics"});
}

// The mission area (server/json/area_json.hpp) and the window of the map a mission planned on.
void addAreaSchemas(json& s) {
  const double maxXY = rover::json::kMaxCoordinateM;
  const json coordinate = {{"type", "number"}, {"minimum", -maxXY}, {"maximum", maxXY}};
  const json position = {{"type", "array"}, {"items", coordinate}, {"minItems", 2}, {"maxItems", 2}};
  json bbox = object({{"bbox", {{"type", "array"}, {"items", coordinate}, {"minItems", 4}, {"maxItems", 4},
                                {"description", "[x0, y0, x1, y1]: metres in the map's local frame, x1 > x0, y1 > y0."}}}},
                     {"bbox"}, true);
  json polygon = object({{"polygon", {{"type", "array"}, {"items", position}, {"minItems", 3},
                                      {"maxItems", static_cast<double>(kMaxAreaVertices + 1)},
                                      {"description", "One ring [[x, y], ...] in the map's local frame (the "
                                                      "closing vertex may be repeated)."}}}},
                        {"polygon"}, true);
  s["MissionArea"] = {
      {"oneOf", {bbox, polygon}},
      {"description",
       "Where the mission plans, at the map's full resolution: only this area and a margin of " +
           std::to_string(kAreaMarginCells) +
           " cells are read and analysed; ground outside it is keep-out. On the map, at least 2 cells each "
           "way, its window at most 4096 x 4096 cells. Required on maps of more than 4096 x 4096 cells."}};
  s["PlanningWindow"] = object(
      {{"origin", {{"type", "array"}, {"items", num()}, {"minItems", 2}, {"maxItems", 2},
                   {"description", "The window's lower-left corner in the map's local frame, metres."}}},
       {"row0", {{"type", "integer"}, {"description", "Its first row on the map (row 0 north)."}}},
       {"col0", {{"type", "integer"}, {"description", "Its first column on the map."}}},
       {"rows", {{"type", "integer"}}},
       {"cols", {{"type", "integer"}}},
       {"cell_size_m", num()}},
      {"origin", "row0", "col0", "rows", "cols"});
  s["PlanningWindow"]["description"] = "The part of the map a mission planned on (the whole map without an area).";
}

}  // namespace

json componentSchemas(const PlannerRegistry& planners) {
  json s = json::object();
  s["Error"] = object(
      {{"error", object({{"code", str("Machine-readable, e.g. invalid_field, not_found.")},
                         {"message", str("In words, without server paths.")},
                         {"field", str("The input at fault: a body field (params.targets, rovers[1].x), "
                                       "a query parameter, a header, or the path part.")}},
                        {"code", "message"})}},
      {"error"});

  // Parameters of each planner, from its own table (the same one the request is checked with).
  std::vector<std::string> names = planners.names();
  std::string pdmPlanners;
  for (const auto& n : names)
    if (planners.get(n).specs().ground == Ground::DemAndPdm) pdmPlanners += (pdmPlanners.empty() ? "" : ", ") + n;
  json anyParams = json::array();
  for (const auto& n : names) {
    json props = json::object();
    for (const auto& info : planners.get(n).params()) props[info.key] = paramSchema(info);
    json p = object(props, {}, true);
    p["description"] = "Parameters of " + n + "; any left out take their defaults (GET /api/planners).";
    s[paramsComponent(n)] = p;
    anyParams.push_back(openapi::ref(paramsComponent(n)));
  }

  const double maxXY = rover::json::kMaxCoordinateM, maxHeading = rover::json::kMaxHeadingDeg;
  json rover = object({{"x", {{"type", "number"}, {"minimum", -maxXY}, {"maximum", maxXY},
                              {"description", "Metres east of the map's lower-left corner."}}},
                       {"y", {{"type", "number"}, {"minimum", -maxXY}, {"maximum", maxXY},
                              {"description", "Metres north of the map's lower-left corner."}}},
                       {"heading", {{"type", "number"}, {"minimum", -maxHeading}, {"maximum", maxHeading},
                                    {"description", "Degrees counter-clockwise from east (0)."}}}},
                      {"x", "y"});
  json request = object(
      {{"map", str("Map id.")},
       {"pdm", nullable(str("PDM id on that map: the probability to search, for the planners whose ground is "
                            "dem_pdm (" + pdmPlanners + ")."))},
       {"planner", {{"type", "string"}, {"enum", names}}},
       {"rovers", {{"type", "array"}, {"minItems", 1}, {"maxItems", rover::json::kMaxRovers}, {"items", rover}}},
       {"params", {{"anyOf", anyParams}}},
       {"pace", {{"type", "number"}, {"minimum", 0}, {"maximum", rover::json::kMaxPace},
                 {"description", "Steps per second while watching (0 = full speed)."}}},
       {"name", nullable(name("The run's label."))},
       {"format", {{"type", "string"}, {"enum", {kMissionFileFormat}}}},
       {"version", integer(1, kMissionFileVersion)},
       {"roverplan", nullable(str("The server version that wrote the mission file (informative)."))},
       {"dem_sha256", nullable({{"type", "string"}, {"pattern", "^[0-9a-f]{64}$"},
                                {"description", "The map's grid digest; a map with another answers 409 map_changed."}})},
       {"map_name", nullable(str("Informative."))},
       {"keep_out", {{"type", "object"}, {"allOf", {openapi::ref("Zones")}}, {"nullable", true},
                     {"description", "Keep-out zones of this mission, in the local frame."}}},
       {"area", {{"type", "object"}, {"allOf", {openapi::ref("MissionArea")}}, {"nullable", true},
                 {"description", "The mission area (null: the whole map)."}}},
       {"used", nullable(object({{"pdm_version", nullable({{"type", "integer"}})},
                                 {"zones_version", nullable({{"type", "integer"}})}}))}},
      {"map", "planner", "rovers"}, true);
  request["properties"]["used"]["description"] =
      "The versions the run used (written by the server, informative in a request): its PDM's, and its "
      "keep_out's when it was the map's saved zone set (keep_out.version as read).";
  // Every field the parser accepts has its schema, and no other.
  for (const char* f : rover::json::kMissionRequestFields)
    if (!request["properties"].contains(f)) throw std::logic_error(std::string("openapi: no schema for ") + f);
  s["MissionRequest"] = request;
  json file = request;
  file["required"] = {"format", "version", "map", "planner", "rovers", "params"};
  file["description"] = "A mission file: everything to run a mission again (POST it to /api/missions).";
  s["MissionFile"] = file;
  // Keep-out zones (server/json/zones_json.hpp): Polygons in the local frame unless ?crs=map.
  json position = {{"type", "array"}, {"items", num()}, {"minItems", 2}, {"maxItems", 3}};
  json ring = {{"type", "array"}, {"items", position}, {"minItems", 4}, {"maxItems", rover::json::kMaxZoneVertices + 1}};
  json polygon = object({{"type", {{"type", "string"}, {"enum", {"Polygon"}}}},
                         {"coordinates", {{"type", "array"}, {"items", ring}, {"minItems", 1}}}},
                        {"type", "coordinates"});
  json feature = object({{"type", {{"type", "string"}, {"enum", {"Feature"}}}},
                         {"geometry", polygon},
                         {"properties", nullable(object({{"name", str()}}))}},
                        {"type", "geometry"});
  s["Zones"] = object({{"type", {{"type", "string"}, {"enum", {"FeatureCollection"}}}},
                       {"features", {{"type", "array"}, {"items", feature}, {"maxItems", rover::json::kMaxZones}}}},
                      {"type", "features"});
  s["Zones"]["description"] = "Keep-out zones: a GeoJSON FeatureCollection of Polygons (at most " +
                              std::to_string(rover::json::kMaxZones) + " zones and " +
                              std::to_string(rover::json::kMaxZoneVertices) + " vertices in all).";
  s.update(collabSchemas(feature));
  s["Zones"]["properties"]["version"] = {{"type", "integer"}, {"minimum", 0},
                                         {"description", "The set's version: +1 per save, 0 when never saved."}};
  addAreaSchemas(s);
  s["MissionLabel"] = object({{"label", name("The run's new label (\"\" clears it).")},
                              {"version", {{"type", "integer"}, {"description", "The version read (or If-Match)."}}}},
                             {"label"}, true);

  s["Mission"] = object(
      {{"id", str()},
       {"map", str()},
       {"pdm", nullable(str())},
       {"label", str()},
       {"version", {{"type", "integer"}, {"description", "+1 per label change; send it back (If-Match) to relabel."}}},
       {"map_name", nullable(str("Null once the map is deleted."))},
       {"pdm_name", nullable(str())},
       {"planner", str()},
       {"status", oneOf<RunStatus>()},
       {"message", str("Why it failed, or its warnings.")},
       {"created_at", str()},
       {"started_at", str()},
       {"finished_at", str()},
       {"metrics", nullable({{"type", "object"}, {"additionalProperties", num()}})},
       {"spec", {{"type", "object"}, {"description", "The request as accepted, with the map's dem_sha256 at launch."}}},
       {"links", object({{"stream", str()}, {"result_json", str()}, {"result_geojson", str()}, {"result_csv", str()}},
                        {"stream", "result_json", "result_geojson", "result_csv"})},
       {"progress", nullable(object({{"fraction", num("0..1")}, {"coverage", num()}, {"moves", num()}, {"step", num()}},
                                    {}, false))},
       {"step", nullable(num())},
       {"result", {{"type", "string"},
                   {"enum", {"pending", "ready", "none"}},
                   {"description", "GET of one mission: its result files are to come (queued, running, or a cancelled "
                                   "run storing its partial result: they answer 409 not_ready), there, or never "
                                   "(409 no_result)."}}}},
      {"id", "map", "planner", "status", "message", "created_at", "links", "spec"});
  s.update(studySchemas());
  s["PlanResult"] = planResultSchema();
  s["Cancelling"] = object({{"id", str()}, {"status", {{"type", "string"}, {"enum", {"cancelling"}}}}}, {"id", "status"});
  s["Deleted"] = object({{"deleted", str("The id deleted.")}}, {"deleted"});

  s["Pdm"] = object({{"id", str()},
                     {"map", str()},
                     {"name", str()},
                     {"created_at", str()},
                     {"version", {{"type", "integer"}, {"description", "1 when created, +1 per change (PUT)."}}},
                     {"kind", {{"type", "string"}, {"enum", {"gaussians", "random", "raster"}}}},
                     {"seed", {{"type", "integer"}}},
                     {"components", {{"type", "array"}, {"items", {{"type", "object"}}}}},
                     {"layer", str("PNG of the PDM.")},
                     {"raster", str("GeoTIFF of the PDM.")}},
                    {"id", "map", "name", "created_at", "layer"});
  json component = object({{"x", num("Metres, local frame.")},
                           {"y", num("Metres, local frame.")},
                           {"sigma_x", {{"type", "number"}, {"exclusiveMinimum", true}, {"minimum", 0}}},
                           {"sigma_y", {{"type", "number"}, {"exclusiveMinimum", true}, {"minimum", 0}}},
                           {"rotation_deg", {{"type", "number"}, {"minimum", -360}, {"maximum", 360}}},
                           {"weight", {{"type", "number"}, {"minimum", 0}, {"maximum", 1e9}}}},
                          {"x", "y", "sigma_x"}, true);
  s["PdmRequest"] = object({{"name", nullable(name("The PDM's name."))},
                            {"components", {{"type", "array"}, {"minItems", 1}, {"maxItems", pdm::kMaxComponents},
                                            {"items", component}}},
                            {"random", integer(1, 100)},
                            {"seed", integer(0, 1.8e19)}});

  s["Map"] = object({{"id", str()},
                     {"name", str()},
                     {"created_at", str()},
                     {"version", {{"type", "integer"}, {"description", "+1 per rename; send it back (If-Match) to rename."}}},
                     {"rows", {{"type", "integer"}}},
                     {"cols", {{"type", "integer"}}},
                     {"cell_size_m", num()},
                     {"cell_height_m", num()},
                     {"width_m", num()},
                     {"height_m", num()},
                     {"crs", str()},
                     {"geographic", {{"type", "boolean"}}},
                     {"driver", str()},
                     {"source_files", {{"type", "array"}, {"items", str()}}},
                     {"dem_sha256", {{"type", "string"}, {"pattern", "^[0-9a-f]{64}$"}}},
                     {"resampling", str()},
                     {"elevation", object({{"min", num()}, {"max", num()}}, {"min", "max"})},
                     {"classes", object({{"traversable_pct", num()}, {"high_risk_pct", num()},
                                         {"impassable_pct", num()}, {"nodata_pct", num()}})},
                     {"body", {{"type", "string"}, {"enum", {"mars", "moon", "earth", "unknown"}}}},
                     {"body_source", {{"type", "string"}, {"enum", {"declared", "crs"}}}},
                     {"vertical_scale", num()},
                     {"vertical_offset", num()},
                     {"warnings", {{"type", "array"},
                                   {"description", "What the cell size and heights say about the map's use by a micro-rover "
                                                   "(never a refusal): coarse_cell (cells over 5 m), heights_look_like_radii "
                                                   "(import again with the vertical_offset the message gives), "
                                                   "heights_out_of_range (outside the body's relief)."},
                                   {"items", object({{"code", {{"type", "string"}, {"enum", {"coarse_cell", "heights_look_like_radii", "heights_out_of_range"}}}},
                                                     {"field", str()}, {"message", str()}},
                                                    {"code", "field", "message"})}}},
                     {"crop", {{"type", "array"}, {"items", num()}, {"minItems", 4}, {"maxItems", 4}}},
                     {"crop_px", {{"type", "array"}, {"items", num()}, {"minItems", 4}, {"maxItems", 4}}},
                     {"layers", {{"type", "object"}, {"additionalProperties", str()}}},
                     {"colour_range", {{"type", "array"}, {"items", num()}, {"minItems", 2}, {"maxItems", 2},
                                       {"description", "The elevation ramp of every tile [low, high] m, fixed at import."}}},
                     {"storage", object({{"elevation", {{"type", "string"}, {"enum", {"raw", "cog"}}, {"description", "How the elevation is stored. raw: a large upload (4 M cells and more) is announced before its elevation is compressed; its tiles, layers and missions work already (the same bytes as later), and it becomes cog within seconds to a minute (the event stream says 'changed'; a server stopped meanwhile compresses it at its next start). cog: a Cloud-Optimised GeoTIFF. Maps stored before have no storage field."}}},
                                         {"codec", {{"type", "string"}, {"enum", {"none", "zstd"}}, {"description", "Its codec: none while raw, zstd (lossless) once a COG."}}},
                                         {"overviews", {{"type", "integer"}, {"description", "Overview levels (one per zoom below native_zoom)."}}}})},
                     {"tiles", nullable(object({{"tile_size", {{"type", "integer"}}},
                                       {"zmin", {{"type", "integer"}}},
                                       {"zmax", {{"type", "integer"}}},
                                       {"native_zoom", {{"type", "integer"}, {"description", "The zoom at which one cell is one tile pixel."}}},
                                       {"resolutions", {{"type", "array"}, {"items", num()}, {"description", "Metres per tile pixel along x, per zoom from 0."}}},
                                       {"resolutions_y", {{"type", "array"}, {"items", num()}, {"description", "Metres per tile pixel along y, per zoom from 0."}}},
                                       {"tile_counts", {{"type", "array"}, {"items", {{"type", "array"}, {"items", {{"type", "integer"}}}}}, {"description", "[across, down] per zoom."}}},
                                       {"extent", {{"type", "array"}, {"items", num()}, {"minItems", 4}, {"maxItems", 4}, {"description", "[0, 0, width_m, height_m] in the local frame (x east, y north)."}}},
                                       {"origin", {{"type", "array"}, {"items", num()}, {"minItems", 2}, {"maxItems", 2}, {"description", "The tile grid's top-left corner in the local frame."}}},
                                       {"url", str("Template of the tile route: {layer}, {z}, {x}, {y}.")}},
                                      {"tile_size", "zmax", "resolutions", "extent", "origin", "url"}))},
                     {"pdms", {{"type", "array"}, {"items", openapi::ref("Pdm")}}},
                     {"pdms_total", {{"type", "integer"}}}},
                    {"id", "name", "created_at", "version", "rows", "cols", "cell_size_m", "layers"});
  s["MapName"] = object({{"name", withMinLength(name("The map's new name, unique among the maps, not blank."))},
                         {"version", {{"type", "integer"}, {"description", "The version read (or If-Match)."}}}},
                        {"name"}, true);
  json upload = json::object();
  upload["file"] = {{"type", "array"}, {"items", {{"type", "string"}, {"format", "binary"}}},
                    {"description", "The DEM's files (one or more parts named file: .IMG + .LBL, a zip, ...)."}};
  upload["name"] = name("The map's name (default: from the file).");
  for (const auto& o : maps::demImportOptionInfos())
    upload[o.key] = {{"type", "string"}, {"pattern", o.pattern}, {"description", o.doc}};
  s["MapUpload"] = object(upload, {"file"});

  s["ParamInfo"] = paramInfoSchema();
  s["Preset"] = object({{"name", str()}, {"doc", str()}, {"params", {{"type", "object"}}}}, {"name", "doc", "params"});
  // What each planner describes of itself (core/planning/planner_specs.hpp), with the enums'
  // names from the JSON edge (server/json/planner_json.hpp).
  s["PlannerMetric"] = object({{"key", str()}, {"unit", str("Empty when dimensionless.")}, {"doc", str()}},
                              {"key", "unit", "doc"});
  s["PlannerStage"] = object({{"name", str()}, {"doc", str()}}, {"name", "doc"});
  s["Planner"] = object(
      {{"name", {{"type", "string"}, {"enum", names}}},
       {"summary", str()},
       {"params", {{"type", "array"}, {"items", openapi::ref("ParamInfo")}}},
       {"presets", {{"type", "array"}, {"items", openapi::ref("Preset")}}},
       {"map_defaults", {{"type", "object"}, {"description", "With ?map=: map, body and the defaults it sets."}}},
       {"ground", {{"type", "string"},
                   {"enum", rover::json::groundNames()},
                   {"description", "What it plans on: coverage_grid (the map resampled to its coverage cell, or "
                                   "a random obstacle grid) or dem_pdm (the map at its own resolution and a PDM)."}}},
       {"starts", {{"type", "string"},
                   {"enum", rover::json::startPlacementNames()},
                   {"description", "Where its rovers start when none are placed (a study's runs)."}}},
       {"progress", object({{"measure", {{"type", "string"}, {"enum", rover::json::progressNames()}}},
                            {"series", str("The result's series that records it.")}},
                           {"measure", "series"})},
       {"seconds_per_run", {{"type", "boolean"}, {"description", "A run takes seconds (a simulated mission)."}}},
       {"metrics", {{"type", "array"}, {"items", openapi::ref("PlannerMetric")}}},
       {"stages", {{"type", "array"}, {"items", openapi::ref("PlannerStage")}}}},
      {"name", "summary", "params", "presets", "ground", "starts", "progress", "seconds_per_run", "metrics", "stages"});
  s["Health"] = object({{"status", {{"type", "string"}, {"enum", {"ok"}}}},
                        {"version", str()},
                        {"maps", {{"type", "integer"}}},
                        {"missions_running", {{"type", "integer"}}},
                        {"missions_queued", {{"type", "integer"}}},
                        {"planners", {{"type", "array"}, {"items", str()}}}},
                       {"status", "version", "planners"});
  return s;
}

}  // namespace rover::api::openapi
