#pragma once
// The team planners' memory model (their part of PlannerSpecs: Planner::memoryEstimate), read off
// the code that holds the memory: per DEM cell the traversability, PDM copies, the terrain edge
// model's grids; per rover RRT* trees; per leg (targets × rovers) the simulated 10 Hz trajectory,
// its replay and the result files, for a leg of about two footprints at nominal speed.
#include <cstdint>

#include "core/common/params.hpp"
#include "core/planning/planner_specs.hpp"

namespace rover::team {

// A team-search / hybrid mission on a DEM of `demCells` cells with the request's `params`
// (targets, footprint_m, nominal_speed: the length of its trajectories); `hybrid`: the hybrid
// planner (each leg also covers the footprint). Throws the parameter parser's Error.
MemoryEstimate missionMemory(std::int64_t demCells, int rovers, bool pdm, const ParamSet& params, bool hybrid);

}  // namespace rover::team
