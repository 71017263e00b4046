#pragma once
// `--area X0,Y0,X1,Y1` of `roverplan mission` and `roverplan coverage` (issue 24): plan in that
// rectangle of the DEM (metres in its local frame, from its lower-left corner) at the DEM's own
// resolution, reading only the area's planning window (core/planning/mission_area.hpp) from the
// file. Positions given (--start, --keep-out, --pdm) and printed or written (--json, --geojson)
// are in the whole DEM's frame.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/planning/mission_area.hpp"
#include "maps/dem_import_options.hpp"
#include "maps/dem_io.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

void addAreaOption(ArgParser& args);

struct AreaDem {
  maps::LoadedDem loaded;          // what is planned on: the whole DEM, or the area's window
  std::optional<MissionArea> area;
  PlanningWindow window;           // the whole DEM when no area
  GridGeometry mapGrid;            // the whole DEM's grid and georeferencing (exports)
  GeoReference mapGeo;
};

// The DEM at `path` as `import` says, or with --area its window alone (then --<cellOption>,
// --crop and --crop-px are refused: an area is planned at the DEM's own resolution). A bad
// --area is a UsageError naming it.
AreaDem loadDemInArea(const ArgParser& args, const std::string& path, const maps::DemImport& import,
                      const std::string& cellOption);

// {"area": ..., "planning_window": {...}} for --json (server/json/area_json.hpp).
nlohmann::json areaJson(const AreaDem& dem);

}  // namespace rover::cli
