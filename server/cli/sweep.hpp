#pragma once
// Experiment sweeps over seeded coverage runs (SPEC §4): configurations × seeds on all cores,
// summarised per configuration and metric. Each run gets world seed = start seed = its seed, so
// every configuration of a preset sees the same worlds and starts (a paired comparison).
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/stats.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/world.hpp"

namespace rover::cli {

struct SweepConfig {
  std::string name;
  coverage::WorldParams world;  // seed replaced per run
  int rovers = 1;
  coverage::CoverageParams params;
  // Coverage levels (fraction of reachable free cells) at which each run's path length ratio is
  // read from its own curve.
  std::vector<double> levels;
};

struct SweepRow {
  std::string config;
  std::string metric;
  std::size_t runs = 0;  // runs in the configuration
  Summary summary;       // over the runs that have a value (count = those)
};

struct SweepOutcome {
  std::vector<SweepRow> rows;
  std::size_t totalRuns = 0;
  std::int64_t totalMoves = 0;
  double wallSeconds = 0;
};

std::vector<SweepConfig> sweepPreset(const std::string& name);  // throws UsageError if unknown
int presetDefaultRuns(const std::string& name);
SweepOutcome runSweep(const std::vector<SweepConfig>& configs, int runs, std::uint64_t firstSeed,
                      unsigned threads);

}  // namespace rover::cli
