#pragma once
// Options of a team mission on the command line, shared by `mission` and `bench mission`: the
// DEM (with --crop/--cell), the PDM source, the rovers and every team planner parameter
// (generated from the planner's table, so the CLI never drifts from the API).
#include <memory>
#include <optional>
#include <string>

#include "core/planning/mission_area.hpp"
#include "core/planning/planner.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

struct MissionSetup {
  PlannerRegistry registry = makeBuiltinRegistry();
  std::string plannerName = "team-search";
  PlanningProblem problem;  // dem, pdm and rovers filled in and validated (the window's frame)
  // With --area (issue 24) the problem is the area's planning window: its result is moved into
  // the whole DEM's frame by window.origin; mapGrid and mapGeo are the whole DEM's.
  std::optional<MissionArea> area;
  PlanningWindow window;
  GridGeometry mapGrid;
  GeoReference mapGeo;
  ParamSet params;
  std::string demPath;
  std::string pdmSource;  // how the PDM was made, for the summary ("random 4, seed 1", a file)
};

void addMissionOptions(ArgParser& args);
// Loads the DEM and the PDM, places the rovers and validates everything through the planner;
// throws UsageError naming the option.
MissionSetup readMissionOptions(const ArgParser& args);

}  // namespace rover::cli
