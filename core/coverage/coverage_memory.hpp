#pragma once
// The coverage planner's memory model (its part of PlannerSpecs: Planner::memoryEstimate), read
// off the code that holds the memory: per grid cell the world (obstacles + heights), the resampled
// DEM, the stream's grid and change log, the planner's per-cell arrays (occupancy, BFS,
// reachability, knowledge maps — one per rover in Voronoi mode); per step the coverage curve; per
// move the trails, tracks, series and the result files built from them. The moves are bounded by
// the step budget (each rover moves at most once a step): the estimate counts max_steps × rovers
// moves, so a mission can never outgrow it however long it runs. A request without max_steps gets
// a budget that keeps the team within kDefaultMovesPerCell moves a cell (stepBudget).
#include <cstdint>

#include "core/common/params.hpp"
#include "core/planning/planner_specs.hpp"

namespace rover::coverage {

// The team's moves a coverage mission may make when the request gives no max_steps, per cell of
// its grid. The planner's own default (20·n steps, each rover moving once a step) lets a mission
// that can never meet its goal (frontier: false on ground its rovers cannot sense) wander
// 20·n·rovers moves; a mission that meets its goal makes 1.35 (1 rover) to 1.9 (64 rovers) moves
// a goal cell, frontier mode a little more.
constexpr std::int64_t kDefaultMovesPerCell = 4;

// The step budget of a coverage mission on a grid of `cells` cells: `requested` (the parsed
// params.max_steps) when the request gives one (`given` true), else min(20·n,
// ⌈kDefaultMovesPerCell·n / rovers⌉), which is written into `params` so the planner runs with the
// steps the estimate counts.
struct StepBudget {
  std::int64_t steps = 0;
  bool given = false;
};
StepBudget stepBudget(ParamSet& params, std::int64_t requested, std::int64_t cells, int rovers);

// A coverage mission on a grid of `cells` cells of `cellSize` metres that runs at most `steps`
// steps; `localisation`: with localisation error modelled (true and believed tracks, issue 15).
// A refusal names params.max_steps when the request set it and the steps are what does not fit.
MemoryEstimate missionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi, StepBudget steps,
                             bool localisation = false);

}  // namespace rover::coverage
