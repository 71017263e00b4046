#include "server/missions/mission_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace rover::missions {

namespace {

// Coverage, bytes per grid cell that do not depend on the rover count: world 9 (u8 obstacle,
// f64 height), resampled DEM 4, traversability while building 1, stream grid 5 and change log 8,
// planner occupancy 4, BFS parent/seen/queue 12, reachability 1 + its flood 5, final states and
// visits 5, one shared knowledge map 5.
constexpr std::uint64_t kCoveragePerCell = 59;
// Voronoi mode: a region index 4 per cell, and per rover a mask, a state and a visit count (6).
constexpr std::uint64_t kVoronoiPerCell = 4, kVoronoiPerRoverCell = 6;
// Per move: the stream's trail pose 12, the track's cell 4 and point 16, the coverage curve 16,
// and the result's JSON tree and text while it is saved — measured: a 1-rover mission on the
// default map (360 000 cells, 459 582 moves) peaked 316 MB over the idle server, ~690 bytes a move.
// Moves: about two per cell to cover.
constexpr std::uint64_t kCoveragePerMove = 700;
// Localisation error (issue 15): per cell the true occupancy 4, true visits 1, last entry 8; per
// move the true and believed points 32 and the error 4 in the track, the stream's believed trail 8,
// the believed path and error series in the result's JSON tree and text (~250, as measured above
// for the path).
constexpr std::uint64_t kLocalisationPerCell = 13, kLocalisationPerMove = 300;
constexpr double kMovesPerGoalCell = 2.0;
// Team planners, per DEM cell: traversability classes 1 (twice), the PDM as given 4, the
// planner's PDM copy 4, the terrain edge model and route search grids ~16, the stream's grid is
// on the coarse search grid (small).
constexpr std::uint64_t kTeamPerCell = 30;
// Per rover: RRT* trees (15 000 iterations a segment), the path and the 10 Hz simulated
// trajectory with its replay. Deliberately generous: a 2-rover team-search mission with a PDM on
// the default map peaked 18 MB over the idle server, estimated 63 MB.
constexpr std::uint64_t kTeamPerRover = 24ull << 20;
// Fixed per mission: the planner's tables, JSON of the spec and metrics, the stream.
constexpr std::uint64_t kPerMission = 4ull << 20;

}  // namespace

MemoryEstimate coverageMissionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi,
                                     double goal, bool localisation) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(cells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  std::uint64_t perCell = kCoveragePerCell;
  if (voronoi && k > 1) perCell += kVoronoiPerCell + kVoronoiPerRoverCell * k;
  const double moves = kMovesPerGoalCell * std::clamp(goal, 0.0, 1.0) * static_cast<double>(n);
  MemoryEstimate e;
  if (localisation) perCell += kLocalisationPerCell;
  const std::uint64_t perMove = kCoveragePerMove + (localisation ? kLocalisationPerMove : 0);
  e.bytes = kPerMission + n * perCell + static_cast<std::uint64_t>(moves) * perMove;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%llu coverage cells of %g m, %llu rover%s%s",
                static_cast<unsigned long long>(n), cellSize, static_cast<unsigned long long>(k),
                k == 1 ? "" : "s", voronoi && k > 1 ? " (voronoi)" : "");
  e.what = buf;
  e.field = "params.coverage_cell";
  return e;
}

MemoryEstimate teamMissionMemory(std::int64_t demCells, int rovers, bool pdm) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(demCells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  MemoryEstimate e;
  e.bytes = kPerMission + n * (kTeamPerCell + (pdm ? 0 : 4)) + k * kTeamPerRover;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%llu map cells, %llu rover%s", static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(k), k == 1 ? "" : "s");
  e.what = buf;
  e.field = "map";
  return e;
}

std::uint64_t defaultMissionMemoryBudget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return 4ull << 30;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageSize) / 2;
}

std::string formatBytes(std::uint64_t bytes) {
  char buf[32];
  if (bytes >= (10ull << 30))
    std::snprintf(buf, sizeof buf, "%.0f GiB", static_cast<double>(bytes) / (1ull << 30));
  else if (bytes >= (1ull << 30))
    std::snprintf(buf, sizeof buf, "%.1f GiB", static_cast<double>(bytes) / (1ull << 30));
  else
    std::snprintf(buf, sizeof buf, "%.0f MiB", std::max(1.0, static_cast<double>(bytes) / (1ull << 20)));
  return buf;
}

}  // namespace rover::missions
