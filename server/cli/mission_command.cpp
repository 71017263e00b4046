// `roverplan mission`: a team mission (paper 001, SPEC §3; hybrid, SPEC §4) on a DEM with a PDM.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/team/team_entry.hpp"
#include "maps/geojson.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/coverage_options.hpp"
#include "server/cli/dem_options.hpp"
#include "server/cli/mission_setup.hpp"
#include "server/cli/mcap_output.hpp"
#include "server/json/area_json.hpp"
#include "server/json/plan_json.hpp"

namespace rover::cli {

namespace {

void printSummary(std::ostream& out, const MissionSetup& s, const PlanResult& r) {
  auto m = [&](const char* key) { return r.metric(key); };
  auto count = [&](const char* key) { return static_cast<long>(m(key)); };
  const GridGeometry& g = s.mapGrid;
  out << std::fixed << std::setprecision(2);
  out << "mission    " << r.planner << " on " << s.demPath << ": " << g.rows << " x " << g.cols
      << " cells of " << g.cellWidth << " m; PDM " << s.pdmSource << "; " << count("rovers")
      << " rovers\n";
  if (s.area) {
    const auto lo = s.area->lo(), hi = s.area->hi();
    out << "area       " << lo.x() << "," << lo.y() << " to " << hi.x() << "," << hi.y() << " m; planned on a "
        << s.window.grid.cols << " x " << s.window.grid.rows << " cell window at (" << s.window.origin.x() << ", "
        << s.window.origin.y() << ") m\n";
  }
  out << "route      " << count("targets") << " targets, route mass " << std::setprecision(4)
      << m("route_score") << "\n";
  out << "legs       " << count("targets_reached") << " reached, " << count("targets_skipped")
      << " skipped, " << count("targets_short") << " short; " << count("replans") << " re-plans, "
      << count("waits") << " waits, " << count("rrt_calls") << " RRT* trees\n";
  out << std::setprecision(1) << "team       mean trajectory " << m("mean_trajectory_m")
      << " m, mission time " << m("mission_time_min") << " min, accumulated probability "
      << std::setprecision(4) << m("accumulated_probability") << " (rover 0 alone "
      << m("single_rover_probability") << ")\n";
  out << std::setprecision(2) << "safety     " << count("collisions") << " collisions, min separation "
      << m("min_separation_m") << " m; " << count("exceedances") << " of " << count("samples")
      << " samples over the attitude limit (" << std::setprecision(4)
      << m("exceedance_fraction") * 100 << " %)\n";
  out << std::setprecision(2) << "reach      " << m("unreachable_area_m2") << " m² unreachable from the start ("
      << count("unreachable_search_cells") << " search cells, probability " << std::setprecision(4)
      << m("unreachable_probability") << "); " << count("targets_no_slot")
      << " rover slots without valid ground\n";
  if (m("keep_out_area_m2") > 0)
    out << std::setprecision(2) << "keep-out   " << m("keep_out_area_m2") << " m² excluded ("
        << count("keep_out_search_cells") << " search cells, probability " << std::setprecision(4)
        << m("keep_out_probability") << ")\n";
  out << std::setprecision(2) << "wall       " << m("plan_wall_s") << " s\n";
  out << "outcome    " << (r.warnings.empty() ? "completed" : "completed with warnings") << "\n";
  for (const auto& w : r.warnings) out << "  warning: " << w << "\n";
  for (const auto& i : r.incidents)
    out << "  " << enumName(i.kind) << " rover " << i.rover << " at t = " << std::setprecision(1) << i.time
        << " s (" << i.position.x() << ", " << i.position.y() << "): " << i.note << "\n";
}

}  // namespace

int missionCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("mission",
                 "A team mission on a DEM (Swinton et al., SPEC §3): LHC_GW_CONV team route over "
                 "the PDM, RRT* per rover and segment, 10 Hz rover simulation, prioritised "
                 "coordination; or the hybrid mission (SPEC §4).");
  addMissionOptions(args);
  args.option("geojson", "FILE", "", "Also write the trajectories, route, targets and incidents as GeoJSON in the map's CRS.");
  args.option("mcap", "FILE", "",
              "Also write the replay as an MCAP file for Foxglove/Lichtblick (poses, fixes, telemetry, terrain, "
              "route, zones, incidents on the mission clock).");
  args.flag("json", "Print one JSON object (metrics, per-rover trajectories, curves, incidents).");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  MissionSetup setup = readMissionOptions(args);
  const Planner& planner = setup.registry.get(setup.plannerName);
  setup.problem.threads = 0;  // the CLI runs one mission: all cores
  PlanResult result = planner.run(setup.problem, setup.params, nullptr, nullptr);
  shiftResult(result, setup.window.origin);  // the area's window → the DEM's frame
  if (args.has("geojson")) {
    const std::string path = args.str("geojson", "");
    std::string text = orUsage([&] { return maps::missionToGeoJson(result, {}, setup.mapGrid, setup.mapGeo); });
    std::ofstream f(path);
    f << text;
    if (!f) throw UsageError(path + ": cannot write");
  }
  if (args.has("mcap")) {
    exports::ReplayInput in;
    in.result = &result;
    in.dem = setup.problem.dem.get();
    in.demOrigin = setup.window.origin;
    in.grid = setup.mapGrid;
    in.geo = setup.mapGeo;
    in.zones = exports::zonesOf(setup.problem.keepOut, setup.window.origin);
    for (const auto& r : setup.problem.rovers) in.startHeadings.push_back(r.heading);
    writeMcapOrFail(in, args.str("mcap", ""));
  }
  if (args.isSet("json")) {
    nlohmann::json j = json::toJson(result);
    const GridGeometry& g = setup.mapGrid;
    j["map"] = {{"dem", setup.demPath}, {"rows", g.rows}, {"cols", g.cols},
                {"cell_size_m", g.cellWidth}, {"pdm", setup.pdmSource}};
    if (setup.area) {  // (only then: a whole-DEM run prints what it printed before the areas)
      j["area"] = json::areaToJson(*setup.area);
      j["planning_window"] = json::windowToJson(setup.window);
    }
    nlohmann::json starts = nlohmann::json::array();
    for (const auto& s : setup.problem.rovers)
      starts.push_back({{"x", s.position.x() + setup.window.origin.x()},
                        {"y", s.position.y() + setup.window.origin.y()},
                        {"heading_deg", s.heading * 180.0 / 3.14159265358979323846}});
    j["starts"] = starts;
    nlohmann::json ps = nlohmann::json::object();
    for (const auto& [k, v] : team::teamParamTable().toSet(team::parseTeamParams(setup.params)))
      ps[k] = json::toJson(v);
    j["params"] = ps;
    out << j.dump() << "\n";
  } else {
    printSummary(out, setup, result);
  }
  return 0;
}

}  // namespace rover::cli
