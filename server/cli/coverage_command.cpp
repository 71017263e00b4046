#include <iomanip>
#include <iostream>

#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/coverage_params.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/coverage_options.hpp"
#include "server/json/plan_json.hpp"

namespace rover::cli {

namespace {

void printSummary(std::ostream& out, const coverage::World& world, const coverage::WorldParams& wp,
                  const coverage::CoverageParams& p, int rovers, const PlanResult& r) {
  auto m = [&](const char* key) { return r.metric(key); };
  const GridGeometry& g = world.geometry();
  out << std::fixed;
  out << "world      " << g.rows << " x " << g.cols << " cells of " << std::setprecision(2)
      << g.cellWidth << " m, " << world.obstacleCount() << " obstacles, "
      << static_cast<long>(m("unreachable_cells")) << " unreachable free cells, seed " << wp.seed
      << "\n";
  out << "planner    " << p.pattern << (p.circumnavigate ? " + circumnavigation" : "")
      << (p.frontier ? " + frontier" : "") << ", " << rovers << " rover(s)"
      << (rovers > 1 ? (p.mode == coverage::TeamMode::Overlap ? ", overlap" : ", voronoi") : "")
      << ", sense radius " << p.senseRadius << ", goal " << std::setprecision(1) << p.coverage * 100
      << " %\n";
  out << "stopped    " << r.stopReason << " after " << static_cast<long>(m("steps")) << " steps\n";
  out << std::setprecision(2) << "coverage   " << m("coverage") * 100 << " % of free cells, "
      << m("coverage_reachable") * 100 << " % of reachable\n";
  out << std::setprecision(3) << "moves      " << static_cast<long>(m("moves"))
      << "  path length ratio " << m("path_length_ratio") << "  makespan "
      << static_cast<long>(m("makespan")) << "\n";
  out << std::setprecision(1) << "distance   " << m("distance_m") << " m   energy " << m("energy_j")
      << " J   max pitch " << std::setprecision(2) << m("max_pitch_deg") << " deg   revisits "
      << static_cast<long>(m("revisits")) << "\n";
}

}  // namespace

int coverageCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("coverage", "Myopic coverage path planning on a random grid world (SPEC §1).");
  addWorldOptions(args);
  addCoverageParamOptions(args);
  args.flag("json", "Print one JSON object (metrics, per-rover paths, coverage curve).");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  coverage::WorldParams wp = readWorldOptions(args);
  const int rovers = static_cast<int>(args.integer("rovers", 1, 1, 64));
  ParamSet params = readCoverageParamOptions(args);

  PlannerRegistry registry = makeBuiltinRegistry();
  const Planner& planner = registry.get("coverage");
  coverage::CoverageParams typed;
  PlanningProblem problem;
  try {
    typed = coverage::parseCoverageParams(params);
    problem.world = coverage::generateWorld(wp);
    problem.rovers = coverage::cellsToStarts(
        problem.world.geometry(), coverage::randomStarts(problem.world, rovers, wp.seed));
    planner.validate(problem, params);
  } catch (const Error& e) {
    throwAsUsage(e);
  }
  PlanResult result = planner.run(problem, params, nullptr, nullptr);

  if (args.isSet("json")) {
    nlohmann::json j = json::toJson(result);
    const GridGeometry& g = problem.world.geometry();
    j["world"] = {{"rows", g.rows},
                  {"cols", g.cols},
                  {"cell_size_m", g.cellWidth},
                  {"obstacle_fraction", wp.obstacleFraction},
                  {"obstacles", problem.world.obstacleCount()},
                  {"sealed_allowed", wp.allowSealed},
                  {"seed", wp.seed}};
    nlohmann::json starts = nlohmann::json::array();
    for (const auto& s : problem.rovers)
      starts.push_back({{"x", s.position.x()},
                        {"y", s.position.y()},
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
