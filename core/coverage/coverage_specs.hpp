#pragma once
// The coverage planner's description (core/planning/planner_specs.hpp): a grid world laid on the
// map at its coverage cell, random starts, the coverage curve, its metrics and stages, and the
// hooks Planner declares for them.
#include <cstdint>
#include <vector>

#include "core/planning/planner.hpp"

namespace rover::coverage {

const PlannerSpecs& coverageSpecs();

// Square cells laid on the map at its own resolution (core/coverage/terrain_world): the cell
// comes from the map when not given and is refused past the grid's cell limit.
MapGround coverageGround(const GridGeometry& map, const ParamSet& params);

// The mission's memory on `ground` laid on `map` (coverage_memory.hpp); bounds max_steps in
// `params` when the request left it to the planner.
MemoryEstimate coverageMemoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers,
                                      ParamSet& params);

// Random distinct starts on free cells of the coverage world's largest free region that also pass
// the planner's start check (a free coverage cell can still sit next to nodata); seeds seed,
// seed + 1, ... are tried in turn (at most 21), after which validate says why.
std::vector<RoverStart> randomValidStarts(const Planner& planner, const PlanningProblem& problem,
                                          const ParamSet& params, int rovers, std::uint64_t seed);

}  // namespace rover::coverage
