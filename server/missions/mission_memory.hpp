#pragma once
// What a mission costs in memory, estimated before it is queued (issue 14: "per-mission memory
// counted against a budget before queueing"), as an upper bound of its peak (issue 22: "budgets
// that are true"). The figures are read off the code that holds the memory:
//   coverage — per grid cell: the world (obstacles + heights), the resampled DEM, the stream's
//              grid and change log, the planner's per-cell arrays (occupancy, BFS, reachability,
//              knowledge maps — one per rover in Voronoi mode); per step the coverage curve; per
//              move the trails, tracks, series and the result files built from them. The moves are
//              bounded by the step budget (each rover moves at most once a step): the estimate
//              counts max_steps × rovers moves, so a mission can never outgrow it however long it
//              runs. A request without max_steps gets a server default that keeps the team within
//              kDefaultMovesPerCell moves a cell (coverageStepBudget);
//   team     — per DEM cell the traversability, PDM copies, the terrain edge model's grids; per
//              rover RRT* trees; per leg (targets × rovers) the simulated 10 Hz trajectory, its
//              replay and the result files, for a leg of about two footprints at nominal speed.
// The planners' own code is the truth; these constants are a model of it, kept next to the budget
// and checked by tests/server/test_mission_peaks.cpp (measured peak <= 1.5 × estimate, per planner).
#include <cstdint>
#include <string>

#include "core/common/params.hpp"

namespace rover::missions {

struct MemoryEstimate {
  std::uint64_t bytes = 0;
  std::string what;   // e.g. "9000000 coverage cells of 0.05 m, 1 rover"
  std::string field;  // the request field that drives it (params.coverage_cell, params.max_steps, map)
  // A coverage mission: bytes = fixedBytes + steps × bytesPerStep, so a refusal can say which
  // max_steps would fit. Zero for the team planners.
  std::uint64_t fixedBytes = 0, bytesPerStep = 0;
};

// The team's moves a server coverage mission may make when the request gives no max_steps, per
// cell of its grid. The planner's own default (20·n steps, each rover moving once a step) lets a
// mission that can never meet its goal (frontier: false on ground its rovers cannot sense)
// wander 20·n·rovers moves; a mission that meets its goal makes 1.35 (1 rover) to 1.9 (64 rovers)
// moves a goal cell, frontier mode a little more.
constexpr std::int64_t kDefaultMovesPerCell = 4;

// The step budget of a coverage mission on a grid of `cells` cells: `requested` (the parsed
// params.max_steps) when the request gives one (`given` true), else min(20·n,
// ⌈kDefaultMovesPerCell·n / rovers⌉), which is written into `params` so the planner runs with the
// steps the estimate counts.
struct StepBudget {
  std::int64_t steps = 0;
  bool given = false;
};
StepBudget coverageStepBudget(ParamSet& params, std::int64_t requested, std::int64_t cells, int rovers);

// A coverage mission on a grid of `cells` cells of `cellSize` metres that runs at most `steps`
// steps; `localisation`: with localisation error modelled (true and believed tracks, issue 15).
// `stepsGiven`: the request set max_steps (then the field a refusal names is params.max_steps).
MemoryEstimate coverageMissionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi,
                                     StepBudget steps, bool localisation = false);
// A team-search / hybrid mission on a DEM of `demCells` cells with the request's `params`
// (targets, footprint_m, nominal_speed: the length of its trajectories); `hybrid`: the hybrid
// planner (each leg also covers the footprint).
MemoryEstimate teamMissionMemory(std::int64_t demCells, int rovers, bool pdm, const ParamSet& params,
                                 bool hybrid);

// The default mission memory budget: half the machine's physical memory (4 GiB if unknown).
std::uint64_t defaultMissionMemoryBudget();

// "1.5 GiB" / "230 MiB" for messages.
std::string formatBytes(std::uint64_t bytes);

}  // namespace rover::missions
