#pragma once
// `roverplan sweep --preset swinton`: paper 001's study (§4) on two sites — the synthetic Mars
// default (600 × 600 × 0.25 m) and the HiRISE Gale patch cropped to 150 × 150 m at 0.25 m — with
// random PDMs (G = 4, one seed per run), 5 rovers and 64 targets. Per PDM it runs the team search
// with LHC_GW_CONV and with the two route baselines (plain LHC, lawnmower), and the hybrid
// mission, so every configuration sees the same PDMs (a paired comparison).
#include <cstdint>
#include <string>
#include <vector>

#include "server/cli/sweep.hpp"

namespace rover::cli {

struct TeamSweepOptions {
  int runs = 20;                     // PDMs per site
  std::uint64_t firstSeed = 1;       // PDM seeds firstSeed, firstSeed + 1, ...; RRT* seed = PDM seed
  unsigned threads = 0;              // missions run in parallel
  unsigned missionThreads = 1;       // threads each mission plans on (0 = all cores)
  std::string hirisePath;            // "" = the synthetic site only
  int rovers = 5;
  int targets = 64;
  std::vector<std::string> configs;  // empty = all: lhc_gw_conv, lhc, lawnmower, hybrid
  // Coordination modes each config runs in ("timed", "paper"); empty = timed only. Paper-mode
  // rows are named "<config>+paper", on the same PDMs.
  std::vector<std::string> coordination;
};

// Distances (mean metres per rover) at which each run's team curve is read, for the route
// comparison "at the same distance".
const std::vector<double>& teamSweepDistances();

SweepOutcome runTeamSweep(const TeamSweepOptions& options, std::ostream& progress);

}  // namespace rover::cli
