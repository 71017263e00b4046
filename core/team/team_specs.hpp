#pragma once
// The team planners' description (core/planning/planner_specs.hpp): the map at its own resolution
// and the PDM, formation starts, the detection curve, their metrics and stages.
#include "core/planning/planner.hpp"

namespace rover::team {

// `hybrid`: the hybrid planner (SPEC §4), whose legs also cover their footprints.
const PlannerSpecs& teamSpecs(bool hybrid);

// `n` rovers in formation around the map's centre, from the team parameters. Throws InvalidInput
// "rovers" when there is no room.
std::vector<RoverStart> formationStarts(const terrain::Dem& dem, const ParamSet& params, int n);

}  // namespace rover::team
