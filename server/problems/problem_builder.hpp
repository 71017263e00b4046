#pragma once
// The one problem builder of the server, the CLI and studies (issue 12): what a planner plans on,
// from a map or a synthetic grid world, and where its rovers start.
//
// The coverage planner plans on a grid world: the map resampled to its coverage cell, or a random
// obstacle grid; the team planners plan on the map at its own resolution and the PDM. Building
// is split in two so a server can check memory before anything big exists: groundOnMap resolves
// the parameters that shape the ground (cheap, throws before any allocation), problemOnMap builds
// it. Errors are core Errors naming the parameter (the caller qualifies the field).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/world.hpp"
#include "core/planning/planner.hpp"
#include "core/terrain/dem.hpp"

namespace rover::problems {

// How a planner's ground is laid on a map, resolved from its parameters.
struct MapGround {
  bool coverageGrid = false;  // the coverage planner: a grid world on the map
  double cell = 0;            // its square cell, m (the resolved coverage_cell)
  terrain::TraversabilityParams traversal;
  coverage::CoverageParams coverage;  // the parsed coverage parameters (coverageGrid only)
};

// `planner` is the planner's registered name; throws the parameter parser's Error.
MapGround groundOnMap(const std::string& planner, const GridGeometry& map, const ParamSet& params);

// The problem on a map: the coverage grid world laid on it (coverageGrid), the map itself, the
// PDM (team planners; null = none) and the map's body: `body` when declared (an upload's or the
// CLI's --body), else the body of the map's CRS. Rovers are left empty.
PlanningProblem problemOnMap(const MapGround& ground, std::shared_ptr<const terrain::Dem> dem,
                             std::shared_ptr<const Raster<float>> pdm = nullptr,
                             std::optional<terrain::Body> body = std::nullopt);

// The problem on a random grid world (coverage planner; no map, no body).
PlanningProblem problemOnGrid(const coverage::WorldParams& world);

// Random distinct starts on free cells of the coverage world's largest free region that also pass
// the planner's start check (a free coverage cell can still sit next to nodata); seeds seed,
// seed + 1, ... are tried in turn (at most 21), after which validate says why.
std::vector<RoverStart> randomValidStarts(const Planner& planner, const PlanningProblem& problem,
                                          const ParamSet& params, int rovers, std::uint64_t seed);

// `n` rovers in formation around the map's centre (team planners), from the team parameters.
// Throws InvalidInput "rovers" when there is no room.
std::vector<RoverStart> formationStarts(const terrain::Dem& dem, const ParamSet& teamParams, int n);

// G random Gaussian components (paper 001: G = 4) of seed `seed`, discretised on the map's cells
// with data.
Raster<float> randomPdm(const terrain::Dem& dem, int components, std::uint64_t seed);

}  // namespace rover::problems
