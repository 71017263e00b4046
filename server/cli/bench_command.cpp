#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "core/common/parallel.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/pdm/pdm.hpp"
#include "core/planning/rover_limits.hpp"
#include "core/team/team_mission.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/localisation_bench.hpp"

namespace rover::cli {

namespace {

struct BenchFigures {
  double seconds = 0;
  std::int64_t moves = 0;
  int runs = 0;
};

// `runs` spiral runs to 95 % on 60×60 with 5 % obstacles (paper 002's default world),
// seeds 1..runs.
BenchFigures benchCoverage(int runs, unsigned threads, bool frontier) {
  coverage::CoverageParams params;
  params.frontier = frontier;
  std::vector<std::int64_t> moves(runs);
  auto t0 = std::chrono::steady_clock::now();
  parallelFor(runs, threads, [&](std::size_t i) {
    coverage::WorldParams wp;
    wp.seed = i + 1;
    auto world = coverage::generateWorld(wp);
    auto res = coverage::runCoverage(world, coverage::randomStarts(world, 1, wp.seed), params);
    moves[i] = res.metrics.moves;
  });
  BenchFigures f;
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (auto m : moves) f.moves += m;
  f.runs = runs;
  return f;
}

void missionHeader(std::ostream& out) {
  out << std::left << std::setw(14) << "planner" << std::setw(8) << "mode" << std::right
      << std::setw(7) << "rovers" << std::setw(9) << "threads"
      << std::setw(10) << "wall s" << std::setw(12) << "RRT* trees" << std::setw(12) << "trees/s"
      << std::setw(12) << "sim s" << std::setw(12) << "collisions" << std::setw(10) << "reached"
      << std::setw(8) << "short" << std::setw(9) << "skipped" << std::setw(11) << "min sep m" << "\n";
}

// Plans one team mission and prints its row; returns the wall time.
double missionRow(std::ostream& out, const terrain::Dem& dem, const Raster<float>& pdm,
                  const std::vector<team::Pose>& starts, team::TeamMissionParams p, bool hybrid) {
  const auto t0 = std::chrono::steady_clock::now();
  team::TeamMissionResult r = team::runTeamMission(dem, pdm, starts, p, hybrid);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out << std::left << std::setw(14) << (hybrid ? "hybrid" : "team-search") << std::setw(8)
      << enumName(p.coordination.mode) << std::right << std::setw(7) << starts.size() << std::setw(9)
      << p.coordination.threads << std::fixed << std::setprecision(2) << std::setw(10) << wall
      << std::setw(12) << r.metrics.rrtCalls << std::setprecision(0) << std::setw(12)
      << r.metrics.rrtCalls / wall << std::setw(12) << r.metrics.missionTimeS << std::setw(12)
      << r.metrics.collisions << std::setw(10) << r.metrics.targetsReached << std::setw(8)
      << r.metrics.targetsShort << std::setw(9) << r.metrics.targetsSkipped + r.metrics.targetsNoSlot
      << std::setprecision(2) << std::setw(11) << r.metrics.minSeparationM;
  return wall;
}

// One paper-scale mission (SPEC §3 defaults): the default synthetic Mars map (600 × 600 × 0.25 m),
// a random PDM (G = 4, seed 1), 5 rovers in formation at the centre, 64 targets, seed 1; team
// search and hybrid, in each coordination mode (timed: ours, paper: paper 001's), on one thread
// and on all cores. The target: median ≤ 5 s, worst ≤ 15 s wall per mission. Then the
// same team-search mission (timed, all cores) for each of `teamSizes` rovers in the generated
// formation (issue 25: ≤ 15 s for 20 rovers, ≤ 60 s for 64).
int benchMission(std::ostream& out, const std::vector<int>& teamSizes) {
  const terrain::Dem dem = maps::generateTerrain({});
  const GridGeometry& g = dem.geometry();
  std::vector<std::uint8_t> valid(g.cellCount(), 1);
  const Raster<float> pdm = pdm::discretise(pdm::randomGaussians(g, 4, 1), g, valid);
  team::TeamMissionParams p;
  const Eigen::Vector2d centre{g.widthMetres() / 2, g.heightMetres() / 2};
  const auto starts = team::formationStarts(dem, p, centre, 5);
  out << "bench mission: synthetic Mars 600x600 x 0.25 m, random PDM (G = 4, seed 1), 5 rovers, "
         "64 targets, seed 1 (target: <= 5 s wall)\n";
  missionHeader(out);
  const unsigned all = hardwareThreads();
  for (team::CoordinationMode mode : {team::CoordinationMode::Timed, team::CoordinationMode::Paper})
  for (bool hybrid : {false, true}) {
    double single = 0;
    p.coordination.mode = mode;
    for (unsigned threads : {1u, all}) {
      p.coordination.threads = threads;
      const double wall = missionRow(out, dem, pdm, starts, p, hybrid);
      if (threads == 1) single = wall;
      if (threads != 1) out << "   speed-up x" << std::setprecision(2) << single / wall;
      out << "\n";
    }
  }
  if (teamSizes.empty()) return 0;
  out << "\nteam size: the same team-search mission, timed, " << all
      << " threads, the generated formation (targets: <= 15 s for 20 rovers, <= 60 s for 64)\n";
  missionHeader(out);
  p.coordination.mode = team::CoordinationMode::Timed;
  p.coordination.threads = all;
  for (int n : teamSizes) {
    missionRow(out, dem, pdm, team::formationStarts(dem, p, centre, n), p, false);
    out << "\n";
  }
  return 0;
}

}  // namespace

int benchCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("bench", "Benchmarks that print their figures. Targets: coverage, mission, "
                         "localisation.");
  args.positional("TARGET", "coverage | mission | localisation");
  args.option("runs", "N", "2000", "Runs per measurement.");
  args.option("team-sizes", "N,N,...", "20,64",
              "mission: the team sizes planned after the 5-rover table.");
  addLocalisationBenchOptions(args);
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (args.positionals()[0] == "mission") {
    std::vector<int> sizes{20, planning::kMaxRovers};
    if (args.has("team-sizes")) {
      sizes.clear();
      for (double n : args.realList("team-sizes")) {
        if (n != std::floor(n) || n < 1 || n > planning::kMaxRovers)
          throw UsageError("--team-sizes: each size must be a whole number from 1 to " +
                           std::to_string(planning::kMaxRovers));
        sizes.push_back(static_cast<int>(n));
      }
    }
    return benchMission(out, sizes);
  }
  if (args.positionals()[0] == "localisation")
    return benchLocalisation(args, static_cast<int>(args.integer("runs", 100, 1, 100000)), out);
  if (args.positionals()[0] != "coverage")
    throw UsageError("unknown benchmark '" + args.positionals()[0] + "' (coverage, mission, localisation)");
  int runs = static_cast<int>(args.integer("runs", 2000, 1, 10000000));
  unsigned all = hardwareThreads();
  out << "bench coverage: spiral to 95 % on 60x60, 5 % obstacles, " << runs
      << " seeded runs per line\n";
  out << std::left << std::setw(22) << "variant" << std::right << std::setw(9) << "threads"
      << std::setw(10) << "wall s" << std::setw(14) << "runs/s" << std::setw(16) << "moves/s"
      << "\n";
  for (bool frontier : {false, true}) {
    double single = 0;
    for (unsigned threads : {1u, all}) {
      BenchFigures f = benchCoverage(runs, threads, frontier);
      if (threads == 1) single = f.seconds;
      out << std::left << std::setw(22) << (frontier ? "spiral+frontier" : "spiral") << std::right
          << std::setw(9) << threads << std::fixed << std::setprecision(3) << std::setw(10)
          << f.seconds << std::setprecision(0) << std::setw(14) << f.runs / f.seconds
          << std::setw(16) << f.moves / f.seconds;
      if (threads != 1) out << "   speed-up x" << std::setprecision(2) << single / f.seconds;
      out << "\n";
    }
  }
  return 0;
}

}  // namespace rover::cli
