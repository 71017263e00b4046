#include <chrono>
#include <iomanip>
#include <iostream>

#include "core/common/parallel.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/sweep.hpp"

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

}  // namespace

int benchCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("bench", "Benchmarks that print their figures. Targets: coverage.");
  args.positional("TARGET", "coverage");
  args.option("runs", "N", "2000", "Runs per measurement.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (args.positionals()[0] != "coverage")
    throw UsageError("unknown benchmark '" + args.positionals()[0] + "' (coverage)");
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
