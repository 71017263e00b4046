#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>

#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/coverage_params.hpp"
#include "server/cli/commands.hpp"
#include <fstream>

#include "core/coverage/terrain_world.hpp"
#include "core/planning/rover_limits.hpp"
#include "maps/geojson.hpp"
#include "maps/georef.hpp"
#include "server/cli/area_option.hpp"
#include "server/cli/coverage_options.hpp"
#include "server/cli/dem_options.hpp"
#include "server/cli/mcap_output.hpp"
#include "server/json/plan_json.hpp"
#include "server/problems/problem_builder.hpp"

namespace rover::cli {

namespace {

void printSummary(std::ostream& out, const coverage::World& world, const coverage::WorldParams& wp,
                  const coverage::CoverageParams& p, int rovers, const PlanResult& r) {
  auto m = [&](const char* key) { return r.metric(key); };
  const GridGeometry& g = world.geometry();
  out << std::fixed;
  out << (world.hasHeights() ? "dem world  " : "world      ") << g.rows << " x " << g.cols << " cells of " << std::setprecision(2)
      << g.cellWidth << " m, " << world.obstacleCount() << " obstacles, "
      << static_cast<long>(m("unreachable_cells")) << " unreachable free cells";
  if (!world.hasHeights()) out << ", seed " << wp.seed;
  out << "\n";
  out << "planner    " << p.pattern << (p.circumnavigate ? " + circumnavigation" : "")
      << (p.frontier ? " + frontier" : "") << ", " << rovers << " rover(s)"
      << (rovers > 1 ? (p.mode == coverage::TeamMode::Overlap ? ", overlap" : ", voronoi") : "")
      << ", sense radius " << p.senseRadius << ", goal " << std::setprecision(1) << p.coverage * 100
      << " %\n";
  out << "stopped    " << enumName(r.stopReason) << " after " << static_cast<long>(m("steps")) << " steps\n";
  out << std::setprecision(2) << "coverage   " << m("coverage") * 100 << " % of free cells, "
      << m("coverage_reachable") * 100 << " % of reachable\n";
  out << std::setprecision(3) << "moves      " << static_cast<long>(m("moves"))
      << "  path length ratio " << m("path_length_ratio") << "  makespan "
      << static_cast<long>(m("makespan")) << "\n";
  out << std::setprecision(1) << "distance   " << m("distance_m") << " m   energy " << m("energy_j")
      << " J   max pitch " << std::setprecision(2) << m("max_pitch_deg") << " deg   revisits "
      << static_cast<long>(m("revisits")) << "\n";
  if (std::any_of(r.metrics.begin(), r.metrics.end(), [](auto& x) { return x.key == "true_coverage"; }))
    out << std::setprecision(2) << "truth      coverage " << m("true_coverage") * 100
        << " % truly (believed " << m("believed_coverage") * 100 << " %), localisation MAE "
        << std::setprecision(3) << m("localisation_mae_m") << " m (max " << m("localisation_max_error_m")
        << " m), map accuracy " << std::setprecision(2) << m("map_accuracy") * 100 << " %, "
        << static_cast<long>(m("bumps")) << " bumps, " << static_cast<long>(m("loop_closures"))
        << " loop closures\n";
  std::string body = "unknown", gravity;
  for (const auto& [k, v] : r.assumptions) {
    if (k == "body") body = v;
    if (k == "gravity") gravity = v;
  }
  out << "body       " << body << ", gravity " << std::setprecision(2) << m("gravity_m_s2")
      << " m/s² (" << gravity << ")\n";
}

}  // namespace

int coverageCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("coverage", "Myopic coverage path planning (SPEC §1) on a random grid world, or on "
                             "a DEM (--dem): impassable cells are obstacles, heights feed β, energy "
                             "and pitch.");
  addWorldOptions(args);
  args.option("dem", "FILE", "", "Plan on this DEM instead of a random world.");
  // --dem-cell resamples the DEM itself (GDAL); --coverage-cell is the planner's grid on it.
  addDemOptions(args, "dem-cell", "native");
  addAreaOption(args);
  args.option("start", "X,Y,DEG[;X,Y,DEG...]", "random",
              "Rover starts in the local frame (metres from the lower-left corner) and headings "
              "(degrees counter-clockwise from east); overrides --rovers.");
  addCoverageParamOptions(args);
  addKeepOutOption(args);
  args.option("geojson", "FILE", "", "Also write the rover paths as GeoJSON in the map's CRS.");
  args.option("mcap", "FILE", "",
              "Also write the replay as an MCAP file for Foxglove/Lichtblick (one move a second: poses, "
              "telemetry, terrain, zones, incidents).");
  args.flag("json", "Print one JSON object (metrics, per-rover paths, coverage curve).");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  coverage::WorldParams wp = readWorldOptions(args);
  int rovers = static_cast<int>(args.integer("rovers", 1, 1, planning::kMaxRovers));
  ParamSet params = readCoverageParamOptions(args);
  std::vector<RoverStart> starts = readStartOption(args);
  if (!starts.empty()) rovers = static_cast<int>(starts.size());

  PlannerRegistry registry = makeBuiltinRegistry();
  const Planner& planner = registry.get("coverage");
  coverage::CoverageParams typed;
  PlanningProblem problem;
  std::optional<AreaDem> area;  // the DEM, or with --area its window (issue 24)
  std::optional<maps::LoadedDem> dem;
  const maps::DemImport import = readDemImport(args, "dem-cell");
  if (args.has("area") && !args.has("dem")) throw UsageError("--area needs --dem");
  if (args.has("dem")) {
    area = loadDemInArea(args, args.str("dem", ""), import, "dem-cell");
    dem = std::move(area->loaded);
  }
  try {
    typed = coverage::parseCoverageParams(params);
    if (dem) {
      // Square cells of coverage_cell metres in the map's local frame, whatever its pixels.
      problem = problems::problemOnMap(planner.groundOnMap(dem->dem.geometry(), params),
                                       std::make_shared<terrain::Dem>(dem->dem), nullptr, import.body);
    } else {
      problem = problems::problemOnGrid(wp);
    }
    problem.keepOut = readKeepOutOption(args, dem ? area->mapGrid : problem.world.geometry());
    if (area && area->area) {
      for (std::size_t i = 0; i < starts.size(); ++i)
        if (!insidePolygon({area->area->outline}, starts[i].position))
          throw UsageError("invalid value for --start: rover " + std::to_string(i) + " starts outside the --area");
      moveIntoWindow(starts, problem.keepOut, area->window, *area->area);
    }
    problem.rovers = !starts.empty() ? starts : planner.defaultStarts(problem, params, rovers, wp.seed);
    planner.validate(problem, params);
  } catch (const Error& e) {
    if (e.field().rfind("rovers", 0) == 0 && !starts.empty())
      throw UsageError(std::string("invalid value for --start: ") + e.what());
    throwAsUsage(e);
  }
  PlanResult result = planner.run(problem, params, nullptr, nullptr);
  const Eigen::Vector2d origin = area ? area->window.origin : Eigen::Vector2d::Zero();
  shiftResult(result, origin);  // an area's window → the DEM's frame
  if (args.has("geojson")) {
    const std::string path = args.str("geojson", "");
    GeoReference geo = dem ? area->mapGeo : GeoReference{};
    std::string text;
    try {
      // Tracks are in the map's local frame: convert through the map's own grid.
      text = maps::missionToGeoJson(result, {}, dem ? area->mapGrid : problem.world.geometry(), geo);
    } catch (const Error& e) {
      throw UsageError(e.what());
    }
    std::ofstream f(path);
    f << text;
    if (!f) throw UsageError(path + ": cannot write");
  }
  if (args.has("mcap")) {
    exports::ReplayInput in;
    in.result = &result;
    in.dem = dem ? &dem->dem : nullptr;
    in.demOrigin = origin;
    in.grid = dem ? area->mapGrid : problem.world.geometry();
    in.geo = dem ? area->mapGeo : GeoReference{};
    in.zones = exports::zonesOf(problem.keepOut, origin);
    for (const auto& r : problem.rovers) in.startHeadings.push_back(r.heading);
    writeMcapOrFail(in, args.str("mcap", ""));
  }

  if (args.isSet("json")) {
    nlohmann::json j = json::toJson(result);
    const GridGeometry& g = problem.world.geometry();
    j["world"] = {{"rows", g.rows},
                  {"cols", g.cols},
                  {"cell_size_m", g.cellWidth},
                  {"obstacles", problem.world.obstacleCount()}};
    if (dem) {
      j["world"]["dem"] = dem->info.path;
      j["world"]["crs"] = dem->info.crsName;
      j["world"]["body"] = terrain::bodyName(problem.body);
      j["world"]["dem_rows"] = area->mapGrid.rows;
      j["world"]["dem_cols"] = area->mapGrid.cols;
      if (area->area) j.update(areaJson(*area));  // a whole-DEM run prints what it printed before
    } else {
      j["world"]["obstacle_fraction"] = wp.obstacleFraction;
      j["world"]["sealed_allowed"] = wp.allowSealed;
      j["world"]["seed"] = wp.seed;
    }
    nlohmann::json starts = nlohmann::json::array();
    for (const auto& s : problem.rovers)
      starts.push_back({{"x", s.position.x() + origin.x()},
                        {"y", s.position.y() + origin.y()},
                        {"heading_deg", s.heading * 180.0 / 3.14159265358979323846}});
    j["starts"] = starts;
    nlohmann::json ps = nlohmann::json::object();
    for (const auto& [k, v] : coverage::coverageParamTable().toSet(typed)) ps[k] = json::toJson(v);
    j["params"] = ps;
    out << j.dump() << "\n";
  } else {
    printSummary(out, problem.world, wp, typed, rovers, result);
  }
  return 0;
}

}  // namespace rover::cli
