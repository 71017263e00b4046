#pragma once
// The one problem builder of the server, the CLI and studies (issue 12): what a planner plans on,
// from a map or a synthetic grid world.
//
// The planner says what ground it reads (PlannerSpecs::ground): a coverage grid laid on the map at
// its cell, or the map at its own resolution and the PDM. Building is split in two so a server can
// check memory before anything big exists: Planner::groundOnMap resolves the parameters that shape
// the ground (cheap, throws before any allocation), problemOnMap builds it; Planner::defaultStarts
// places rovers the caller did not. Errors are core Errors naming the parameter (the caller
// qualifies the field).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/coverage/world.hpp"
#include "core/planning/planner.hpp"
#include "core/terrain/dem.hpp"

namespace rover::problems {

// The problem on a map: the coverage grid world laid on it (a CoverageGrid ground), the map itself,
// the PDM (a DemAndPdm ground; null = none) and the map's body: `body` when declared (an upload's or the
// CLI's --body), else the body of the map's CRS. Rovers are left empty.
PlanningProblem problemOnMap(const MapGround& ground, std::shared_ptr<const terrain::Dem> dem,
                             std::shared_ptr<const Raster<float>> pdm = nullptr,
                             std::optional<terrain::Body> body = std::nullopt);

// The problem on a random grid world (coverage planner; no map, no body).
PlanningProblem problemOnGrid(const coverage::WorldParams& world);

// G random Gaussian components (paper 001: G = 4) of seed `seed`, discretised on the map's cells
// with data.
Raster<float> randomPdm(const terrain::Dem& dem, int components, std::uint64_t seed);

// Every cell `inArea` marks (and with data) the same mass, summing to 1: a mission area's
// "no PDM" (issue 24), so the probability the team planners report lies in the area, not in the
// keep-out margin of its window. Throws InvalidInput if no such cell exists.
Raster<float> uniformPdm(const terrain::Dem& dem, const std::vector<std::uint8_t>& inArea);

}  // namespace rover::problems
