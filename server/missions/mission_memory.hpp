#pragma once
// What a mission costs in memory, estimated before it is queued (issue 14: "per-mission memory
// counted against a budget before queueing"). The figures are upper-ish bounds read off the code
// that holds the memory, per cell of the grid the planner works on:
//   coverage — the world (obstacles + heights), the resampled DEM, the stream's grid and change
//              log, the planner's per-cell arrays (occupancy, BFS, reachability, knowledge maps —
//              one per rover in Voronoi mode), and the result: trails, tracks, series and their
//              JSON, for about two moves per cell to cover (1 rover on the default map made 1.35
//              moves per cell of its goal, 64 rovers 1.9; measured peak ~690 bytes a move);
//   team     — the DEM's traversability, PDM copies, the terrain edge model's grids, plus a fixed
//              share per rover for RRT* trees and the simulated trajectory.
// The planners' own code is the truth; these constants are a model of it, kept next to the budget.
#include <cstdint>
#include <string>

namespace rover::missions {

struct MemoryEstimate {
  std::uint64_t bytes = 0;
  std::string what;   // e.g. "9000000 coverage cells of 0.05 m, 1 rover"
  std::string field;  // the request field that drives it (params.coverage_cell, map, rovers)
};

// A coverage mission on a grid of `cells` cells of `cellSize` metres, to cover the fraction `goal`;
// `localisation`: with localisation error modelled (true and believed tracks, issue 15).
MemoryEstimate coverageMissionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi,
                                     double goal = 0.95, bool localisation = false);
// A team-search / hybrid mission on a DEM of `demCells` cells.
MemoryEstimate teamMissionMemory(std::int64_t demCells, int rovers, bool pdm);

// The default mission memory budget: half the machine's physical memory (4 GiB if unknown).
std::uint64_t defaultMissionMemoryBudget();

// "1.5 GiB" / "230 MiB" for messages.
std::string formatBytes(std::uint64_t bytes);

}  // namespace rover::missions
