#include "server/cli/mission_setup.hpp"

#include "core/team/team_entry.hpp"
#include "core/planning/rover_limits.hpp"
#include "maps/georef.hpp"
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

}  // namespace

void addMissionOptions(ArgParser& a) {
  a.option("dem", "FILE", "", "The DEM to plan on (any raster GDAL reads). Required.");
  addDemOptions(a, "cell", "native");
  addPdmOptions(a, missionPdmNames());
  a.option("planner", "NAME", "team-search", "team-search | hybrid.");
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
  if (s.plannerName != "team-search" && s.plannerName != "hybrid")
    throw UsageError("invalid value for --planner: '" + s.plannerName + "' (team-search | hybrid)");
  s.params = readParamOptions(a, team::teamParamTable().infos());
  try {
    (void)team::parseTeamParams(s.params);  // a bad parameter is refused before the DEM is read
  } catch (const Error& e) {
    throwAsUsage(e);
  }
  s.demPath = a.str("dem", "");
  const maps::DemImport import = readDemImport(a, "cell");
  maps::LoadedDem loaded = loadDemOrFail(s.demPath, import.load);
  auto dem = std::make_shared<terrain::Dem>(std::move(loaded.dem));
  const PdmOptionNames names = missionPdmNames();
  Raster<float> pdm = readPdmOptions(a, *dem, names, true);
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
  s.problem = problems::problemOnMap(problems::groundOnMap(s.plannerName, dem->geometry(), s.params), dem,
                                     pdm.empty() ? nullptr : std::make_shared<Raster<float>>(std::move(pdm)),
                                     import.body);

  s.problem.keepOut = readKeepOutOption(a, dem->geometry());
  std::vector<RoverStart> starts = readStartOption(a);
  if (starts.empty()) {
    const int n = static_cast<int>(a.integer("rovers", 5, 1, planning::kMaxRovers));
    starts = orUsage([&] { return problems::formationStarts(*dem, s.params, n); });
  }
  s.problem.rovers = starts;
  try {
    s.registry.get(s.plannerName).validate(s.problem, s.params);
  } catch (const Error& e) {
    if (e.field().rfind("rovers", 0) == 0) throw UsageError(std::string("invalid value for --start: ") + e.what());
    if (e.field() == "map" || e.field() == "pdm") throw UsageError(e.what());
    throwAsUsage(e);
  }
  return s;
}

}  // namespace rover::cli
