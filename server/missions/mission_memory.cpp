#include "server/missions/mission_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/team/team_entry.hpp"

namespace rover::missions {

namespace {

// Coverage, bytes per grid cell that do not depend on the rover count: world 9 (u8 obstacle,
// f64 height), resampled DEM 4, traversability while building 1, stream grid 5 and change log 8,
// planner occupancy 4, BFS parent/seen/queue 12, reachability 1 + its flood 5, final states and
// visits 5, one shared knowledge map 5.
constexpr std::uint64_t kCoveragePerCell = 59;
// Voronoi mode: a region index 4 per cell, and per rover a mask, a state and a visit count (6).
constexpr std::uint64_t kVoronoiPerCell = 4, kVoronoiPerRoverCell = 6;
// Per step: the planner's curve point 32 (up to twice that while its vector grows), the result's
// curve series 16, its JSON tree 32 and text ~30.
constexpr std::uint64_t kCoveragePerStep = 140;
// Per move: the stream's trail pose 12, the track's cell and pitch 8 and point 16, the pitch
// series 16, the result's JSON tree and text, the GeoJSON and the CSV while they are formatted.
// Measured: a 1-rover mission on the default map (360 000 cells, 459 582 moves) peaked 316 MB
// over the idle server, ~690 bytes a move and step together.
constexpr std::uint64_t kCoveragePerMove = 560;
// Localisation error (issue 15): per cell the true occupancy 4, true visits 1, last entry 8; per
// move the true and believed points 32 and the error 4 in the track, the stream's believed trail 8,
// the believed path and error series in the result's JSON tree and text (~250, as measured above
// for the path).
constexpr std::uint64_t kLocalisationPerCell = 13, kLocalisationPerMove = 300;
// Team planners, per DEM cell: traversability classes 1 (twice), the PDM as given 4, the
// planner's PDM copy 4, the terrain edge model and route search grids ~16, the stream's grid is
// on the coarse search grid (small).
constexpr std::uint64_t kTeamPerCell = 30;
// Per rover: RRT* trees (15 000 iterations a segment) and the planned path's buffers.
constexpr std::uint64_t kTeamPerRover = 24ull << 20;
// Per simulated sample (10 Hz): the trajectory's sample, the result track's sample, the
// replay's and the series' share, the CSV row and the JSON while the result is written.
constexpr std::uint64_t kTeamPerSample = 400;
// A leg's length in footprints (the route steps to a neighbouring search cell, √2 on a diagonal,
// plus the turn and the slot offset) and its duration factor over nominal speed (slopes, turns).
constexpr double kLegFootprints = 2.0, kLegSlowdown = 1.5;
// Fixed per mission: the planner's tables, JSON of the spec and metrics, the stream.
constexpr std::uint64_t kPerMission = 4ull << 20;

}  // namespace

StepBudget coverageStepBudget(ParamSet& params, std::int64_t requested, std::int64_t cells, int rovers) {
  if (requested > 0) return {requested, true};  // 0 is the planner's "default": bounded below
  const std::int64_t n = std::max<std::int64_t>(cells, 1), k = std::max(rovers, 1);
  StepBudget b;
  b.steps = std::min(20 * n, (kDefaultMovesPerCell * n + k - 1) / k);
  params["max_steps"] = b.steps;
  return b;
}

MemoryEstimate coverageMissionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi,
                                     StepBudget steps, bool localisation) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(cells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  std::uint64_t perCell = kCoveragePerCell;
  if (voronoi && k > 1) perCell += kVoronoiPerCell + kVoronoiPerRoverCell * k;
  if (localisation) perCell += kLocalisationPerCell;
  const std::uint64_t perMove = kCoveragePerMove + (localisation ? kLocalisationPerMove : 0);
  MemoryEstimate e;
  e.fixedBytes = kPerMission + n * perCell;
  e.bytesPerStep = kCoveragePerStep + k * perMove;  // every rover moves at most once a step
  // In floating point: max_steps may be 1e9 with 64 rovers (the product overflows nothing there).
  const double bytes = static_cast<double>(e.fixedBytes) +
                       static_cast<double>(std::max<std::int64_t>(steps.steps, 0)) * static_cast<double>(e.bytesPerStep);
  e.bytes = bytes >= 1.8e19 ? ~0ull : static_cast<std::uint64_t>(bytes);
  char buf[200];
  std::snprintf(buf, sizeof buf, "%llu coverage cells of %g m, %llu rover%s%s, up to %lld steps",
                static_cast<unsigned long long>(n), cellSize, static_cast<unsigned long long>(k),
                k == 1 ? "" : "s", voronoi && k > 1 ? " (voronoi)" : "", static_cast<long long>(steps.steps));
  e.what = buf;
  // What to change: the steps the request asked for when they are what does not fit.
  e.field = steps.given && e.fixedBytes < e.bytes / 2 ? "params.max_steps" : "params.coverage_cell";
  return e;
}

MemoryEstimate teamMissionMemory(std::int64_t demCells, int rovers, bool pdm, const ParamSet& params,
                                 bool hybrid) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(demCells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  const team::TeamPlannerParams p = team::parseTeamParams(params);
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
  e.bytes = kPerMission + n * (kTeamPerCell + (pdm ? 0 : 4)) + k * kTeamPerRover +
            legs * samplesPerLeg * kTeamPerSample;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%llu map cells, %llu rover%s, %llu legs", static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(k), k == 1 ? "" : "s", static_cast<unsigned long long>(legs));
  e.what = buf;
  e.field = legs * samplesPerLeg * kTeamPerSample > n * kTeamPerCell ? "params.targets" : "map";
  return e;
}

std::uint64_t defaultMissionMemoryBudget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return 4ull << 30;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageSize) / 2;
}

std::string formatBytes(std::uint64_t bytes) {
  char buf[32];
  if (bytes >= (10ull << 40))
    std::snprintf(buf, sizeof buf, "%.0f TiB", static_cast<double>(bytes) / (1ull << 40));
  else if (bytes >= (10ull << 30))
    std::snprintf(buf, sizeof buf, "%.0f GiB", static_cast<double>(bytes) / (1ull << 30));
  else if (bytes >= (1ull << 30))
    std::snprintf(buf, sizeof buf, "%.1f GiB", static_cast<double>(bytes) / (1ull << 30));
  else
    std::snprintf(buf, sizeof buf, "%.0f MiB", std::max(1.0, static_cast<double>(bytes) / (1ull << 20)));
  return buf;
}

}  // namespace rover::missions
