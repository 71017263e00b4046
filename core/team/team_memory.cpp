#include "core/team/team_memory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/team/team_entry.hpp"

namespace rover::team {

namespace {

// Per DEM cell: traversability classes 1 (twice), the PDM as given 4, the planner's PDM copy 4,
// the terrain edge model and route search grids ~16, the stream's grid is on the coarse search
// grid (small).
constexpr std::uint64_t kPerCell = 30;
// Per rover: RRT* trees (15 000 iterations a segment) and the planned path's buffers.
constexpr std::uint64_t kPerRover = 24ull << 20;
// Per simulated sample (10 Hz): the trajectory's sample, the result track's sample, the
// replay's and the series' share, the CSV row and the JSON while the result is written.
constexpr std::uint64_t kPerSample = 400;
// A leg's length in footprints (the route steps to a neighbouring search cell, √2 on a diagonal,
// plus the turn and the slot offset) and its duration factor over nominal speed (slopes, turns).
constexpr double kLegFootprints = 2.0, kLegSlowdown = 1.5;

}  // namespace

MemoryEstimate missionMemory(std::int64_t demCells, int rovers, bool pdm, const ParamSet& params, bool hybrid) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(demCells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  const TeamPlannerParams p = parseTeamParams(params);
  const auto& c = p.mission.coordination.controller;
  double legMetres = kLegFootprints * p.mission.footprint;
  if (hybrid) {
    // Each rover also covers the footprint (its Voronoi share) on hybrid_cell_m cells, about two
    // moves a cell to cover.
    const double cells = std::pow(p.mission.footprint / p.mission.hybridCell, 2.0);
    const double share = p.mission.hybridVoronoi ? 1.0 / static_cast<double>(k) : 1.0;
    legMetres += 2.0 * p.mission.hybridCoverage * cells * share * p.mission.hybridCell;
  }
  const double legSeconds = legMetres / c.nominalSpeed * kLegSlowdown;
  const auto samplesPerLeg = static_cast<std::uint64_t>(std::ceil(legSeconds / c.samplePeriod));
  const auto legs = static_cast<std::uint64_t>(std::max(p.mission.route.targets, 1)) * k;
  MemoryEstimate e;
  e.bytes = kMissionFixedBytes + n * (kPerCell + (pdm ? 0 : 4)) + k * kPerRover + legs * samplesPerLeg * kPerSample;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%llu map cells, %llu rover%s, %llu legs", static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(k), k == 1 ? "" : "s", static_cast<unsigned long long>(legs));
  e.what = buf;
  e.field = legs * samplesPerLeg * kPerSample > n * kPerCell ? "params.targets" : "map";
  return e;
}

}  // namespace rover::team
