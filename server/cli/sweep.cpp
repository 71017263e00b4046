#include "server/cli/sweep.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/common/parallel.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

namespace {

std::string percentLabel(double level) {
  std::ostringstream s;
  s << std::round(level * 1000) / 10 << "%";
  return s.str();
}

SweepConfig single(std::string name, const std::string& pattern, bool circumnavigate, bool frontier,
                   bool allowSealed, std::vector<double> levels) {
  SweepConfig c;
  c.name = std::move(name);
  c.world.rows = c.world.cols = 60;
  c.world.obstacleFraction = 0.05;
  c.world.allowSealed = allowSealed;
  c.params.pattern = pattern;
  c.params.circumnavigate = circumnavigate;
  c.params.frontier = frontier;
  c.params.coverage = 1.0;  // run to the end; lower levels are read from each run's curve
  c.levels = std::move(levels);
  return c;
}

}  // namespace

int presetDefaultRuns(const std::string& name) {
  return name == "frontier" ? 1000 : 3000;
}

std::vector<SweepConfig> sweepPreset(const std::string& name) {
  std::vector<SweepConfig> out;
  if (name == "laine-fig6") {
    // Paper 002 fig. 6: 4 single-rover variants, 60×60, 5 % obstacles, every free cell
    // reachable (their §3.2 assumption), path length ratio at 90..100 % coverage.
    const std::vector<double> levels{0.90, 0.95, 0.97, 0.99, 1.00};
    out.push_back(single("spiral", "spiral", false, false, false, levels));
    out.push_back(single("spiral+circ", "spiral", true, false, false, levels));
    out.push_back(single("boustrophedon", "boustrophedon", false, false, false, levels));
    out.push_back(single("boustrophedon+circ", "boustrophedon", true, false, false, levels));
  } else if (name == "laine-fig8") {
    // Paper 002 fig. 8: overlap vs Voronoi for 2, 4, 8 rovers on 30², 60², 100² at 95 %, with the
    // best single-rover pattern (spiral, no circumnavigation).
    for (int size : {30, 60, 100}) {
      for (int rovers : {2, 4, 8}) {
        for (auto mode : {coverage::TeamMode::Overlap, coverage::TeamMode::Voronoi}) {
          SweepConfig c;
          c.name = std::to_string(size) + "x" + std::to_string(size) + "/" +
                   std::to_string(rovers) + "r/" +
                   (mode == coverage::TeamMode::Overlap ? "overlap" : "voronoi");
          c.world.rows = c.world.cols = size;
          c.rovers = rovers;
          c.params.mode = mode;
          c.params.coverage = 0.95;
          out.push_back(c);
        }
      }
    }
  } else if (name == "frontier") {
    // Ours vs the best paper-002 variant, default worlds (sealed regions allowed), run until all
    // reachable cells are covered or the step budget ends.
    const std::vector<double> levels{0.95, 0.99, 1.00};
    out.push_back(single("spiral", "spiral", false, false, true, levels));
    out.push_back(single("spiral+frontier", "spiral", false, true, true, levels));
  } else {
    throw UsageError("unknown preset '" + name + "' (laine-fig6, laine-fig8, frontier)");
  }
  return out;
}

SweepOutcome runSweep(const std::vector<SweepConfig>& configs, int runs, std::uint64_t firstSeed,
                      unsigned threads) {
  struct Record {
    std::vector<double> levelRatio;  // NaN where the level was never reached
    double pathLengthRatio, makespan, makespanRatio, coverageReachable, unreachable;
    std::int64_t moves;
    bool budget;
  };
  const std::size_t total = configs.size() * static_cast<std::size_t>(runs);
  std::vector<Record> records(total);
  auto t0 = std::chrono::steady_clock::now();
  parallelFor(total, threads, [&](std::size_t i) {
    const SweepConfig& c = configs[i / runs];
    std::uint64_t seed = firstSeed + i % runs;
    coverage::WorldParams wp = c.world;
    wp.seed = seed;
    coverage::World world = coverage::generateWorld(wp);
    auto res =
        coverage::runCoverage(world, coverage::randomStarts(world, c.rovers, seed), c.params);
    Record& r = records[i];
    const double n = res.metrics.cells;
    for (double level : c.levels) {
      std::int64_t m = coverage::movesToReach(res, level);
      r.levelRatio.push_back(m < 0 ? std::nan("") : static_cast<double>(m) / n);
    }
    r.pathLengthRatio = res.metrics.pathLengthRatio;
    r.makespan = static_cast<double>(res.metrics.makespan);
    r.makespanRatio = res.metrics.makespanRatio;
    r.coverageReachable = res.metrics.coverageReachable;
    r.unreachable = res.metrics.unreachableCells;
    r.moves = res.metrics.moves;
    r.budget = res.stop == coverage::StopReason::StepBudget;
  });
  SweepOutcome out;
  out.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.totalRuns = total;

  for (std::size_t ci = 0; ci < configs.size(); ++ci) {
    const SweepConfig& c = configs[ci];
    auto column = [&](auto get) {
      std::vector<double> v;
      for (int k = 0; k < runs; ++k) {
        double x = get(records[ci * runs + k]);
        if (!std::isnan(x)) v.push_back(x);
      }
      return v;
    };
    auto row = [&](std::string metric, std::vector<double> values) {
      out.rows.push_back(
          {c.name, std::move(metric), static_cast<std::size_t>(runs), summarize(values)});
    };
    for (std::size_t li = 0; li < c.levels.size(); ++li)
      row("path_length_ratio@" + percentLabel(c.levels[li]),
          column([&](const Record& r) { return r.levelRatio[li]; }));
    row("path_length_ratio", column([](const Record& r) { return r.pathLengthRatio; }));
    if (c.rovers > 1) {
      row("makespan", column([](const Record& r) { return r.makespan; }));
      row("makespan_ratio", column([](const Record& r) { return r.makespanRatio; }));
    }
    row("coverage_reachable", column([](const Record& r) { return r.coverageReachable; }));
    row("unreachable_cells", column([](const Record& r) { return r.unreachable; }));
    row("stopped_by_budget", column([](const Record& r) { return r.budget ? 1.0 : 0.0; }));
    for (int k = 0; k < runs; ++k) out.totalMoves += records[ci * runs + k].moves;
  }
  return out;
}

}  // namespace rover::cli
