#pragma once
// The myopic coverage family as a registered planner named "coverage".
#include <memory>

#include "core/coverage/coverage_planner.hpp"
#include "core/planning/planner.hpp"

namespace rover::coverage {

std::unique_ptr<Planner> makeCoveragePlanner();

// Rover starts in the local frame -> grid cells and the nearest of the 8 headings.
// Throws InvalidInput naming rovers[k] for a start outside the grid.
std::vector<StartCell> startsToCells(const GridGeometry& g, const std::vector<RoverStart>& rovers);
std::vector<RoverStart> cellsToStarts(const GridGeometry& g, const std::vector<StartCell>& starts);

// The coverage parameters whose defaults depend on the map (issue 11): coverage_cell (the map's
// own cell, or the smallest that fits the default cell budget) and, when the map's body is known,
// gravity. The server shows them per map; the planner resolves the same values when not given.
ParamSet coverageMapDefaults(const GridGeometry& map, terrain::Body body);

// The planner-neutral view of a coverage result (metric keys as in the CLI's JSON). metricsOnly
// (PlanningProblem::metricsOnly): the metrics, incidents and the coverage curve, without the
// tracks' points and the per-move series.
PlanResult toPlanResult(const CoverageResult& r, const GridGeometry& g, bool metricsOnly = false);

}  // namespace rover::coverage
