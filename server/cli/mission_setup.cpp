#include "server/cli/mission_setup.hpp"

#include "core/common/strings.hpp"
#include "core/team/team_entry.hpp"
#include "core/planning/rover_limits.hpp"
#include "maps/georef.hpp"
#include "server/cli/area_option.hpp"
#include "server/cli/coverage_options.hpp"
#include "server/cli/dem_options.hpp"
#include "server/problems/problem_builder.hpp"

namespace rover::cli {

namespace {

PdmOptionNames missionPdmNames() {
  PdmOptionNames n;
  n.gaussians = "pdm";
  n.random = "random-pdm";
  n.raster = "pdm-raster";
  n.seed = "pdm-seed";
  return n;
}

// The planners this command runs: those that plan on a DEM and a PDM, whose parameters are the
// team table's.
std::string demPlanners(const PlannerRegistry& registry) {
  std::vector<std::string> names;
  for (const auto& n : registry.names())
    if (registry.get(n).specs().ground == Ground::DemAndPdm) names.push_back(n);
  return join(names, " | ");
}

}  // namespace

void addMissionOptions(ArgParser& a) {
  a.option("dem", "FILE", "", "The DEM to plan on (any raster GDAL reads). Required.");
  addDemOptions(a, "cell", "native");
  addAreaOption(a);
  addPdmOptions(a, missionPdmNames());
  a.option("planner", "NAME", "team-search", demPlanners(makeBuiltinRegistry()) + ".");
  a.option("rovers", "N", "5", "Number of rovers, placed in formation around the map centre.");
  a.option("start", "X,Y,DEG[;X,Y,DEG...]", "formation",
           "Rover starts in the local frame (metres from the lower-left corner) and headings "
           "(degrees counter-clockwise from east); overrides --rovers.");
  addKeepOutOption(a);
  addParamOptions(a, team::teamParamTable().infos());
}

MissionSetup readMissionOptions(const ArgParser& a) {
  MissionSetup s;
  if (!a.has("dem")) throw UsageError("missing option --dem FILE");
  s.plannerName = a.str("planner", "team-search");
  const Planner* planner = s.registry.find(s.plannerName);
  if (!planner || planner->specs().ground != Ground::DemAndPdm)
    throw UsageError("invalid value for --planner: '" + s.plannerName + "' (" + demPlanners(s.registry) + ")");
  s.params = readParamOptions(a, planner->params());
  try {
    planner->checkParams(s.params);  // a bad parameter is refused before the DEM is read
  } catch (const Error& e) {
    throwAsUsage(e);
  }
  s.demPath = a.str("dem", "");
  const maps::DemImport import = readDemImport(a, "cell");
  AreaDem loaded = loadDemInArea(a, s.demPath, import, "cell");
  s.area = loaded.area;
  s.window = loaded.window;
  s.mapGrid = loaded.mapGrid;
  s.mapGeo = loaded.mapGeo;
  auto dem = std::make_shared<terrain::Dem>(std::move(loaded.loaded.dem));
  const PdmOptionNames names = missionPdmNames();
  std::optional<PdmArea> pdmArea;
  if (s.area) pdmArea = PdmArea{s.mapGrid, s.window, cellsInArea(areaInWindow(*s.area, s.window), s.window.grid)};
  Raster<float> pdm = readPdmOptions(a, *dem, names, true, pdmArea ? &*pdmArea : nullptr);
  // No PDM in an area: uniform over the area (not over its window's keep-out margin).
  if (pdm.empty() && pdmArea) pdm = orUsage([&] { return problems::uniformPdm(*dem, pdmArea->inArea); });
  if (a.has(names.random)) {
    s.pdmSource = "random " + a.str(names.random, "") + " Gaussians, seed " +
                  (a.has(names.seed) ? a.str(names.seed, "") : a.str("seed", "1"));
  } else if (a.has(names.gaussians)) {
    s.pdmSource = a.str(names.gaussians, "");
  } else if (a.has(names.raster)) {
    s.pdmSource = a.str(names.raster, "");
  } else {
    s.pdmSource = "uniform";
  }
  s.problem = problems::problemOnMap(planner->groundOnMap(dem->geometry(), s.params), dem,
                                     pdm.empty() ? nullptr : std::make_shared<Raster<float>>(std::move(pdm)),
                                     import.body);

  s.problem.keepOut = readKeepOutOption(a, s.mapGrid);
  std::vector<RoverStart> starts = readStartOption(a);
  if (s.area) {
    for (std::size_t i = 0; i < starts.size(); ++i)
      if (!insidePolygon({s.area->outline}, starts[i].position))
        throw UsageError("invalid value for --start: rover " + std::to_string(i) + " starts outside the --area");
    moveIntoWindow(starts, s.problem.keepOut, s.window, *s.area);  // formation starts below are the window's
  }
  if (starts.empty()) {
    const int n = static_cast<int>(a.integer("rovers", 5, 1, planning::kMaxRovers));
    starts = orUsage([&] { return planner->defaultStarts(s.problem, s.params, n, 0); });
  }
  s.problem.rovers = starts;
  try {
    planner->validate(s.problem, s.params);
  } catch (const Error& e) {
    if (e.field().rfind("rovers", 0) == 0) throw UsageError(std::string("invalid value for --start: ") + e.what());
    if (e.field() == "map" || e.field() == "pdm") throw UsageError(e.what());
    throwAsUsage(e);
  }
  return s;
}

}  // namespace rover::cli
