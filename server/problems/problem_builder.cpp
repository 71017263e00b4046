#include "server/problems/problem_builder.hpp"

#include <cmath>

#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/pdm/pdm.hpp"
#include "core/team/team_entry.hpp"
#include "maps/georef.hpp"

namespace rover::problems {

MapGround groundOnMap(const std::string& planner, const GridGeometry& map, const ParamSet& params) {
  MapGround g;
  // The one place that knows which family plans on a grid world: the coverage planner.
  g.coverageGrid = planner == "coverage";
  if (!g.coverageGrid) return g;
  g.coverage = coverage::parseCoverageParams(params);
  // Square cells laid on the map at its own resolution (core/coverage/terrain_world); the cell
  // comes from the map when not given and is refused past the grid's cell limit.
  g.cell = coverage::resolveCoverageCell(map, g.coverage.coverageCell, g.coverage.cellBudget);
  g.traversal = g.coverage.traversability();
  return g;
}

PlanningProblem problemOnMap(const MapGround& ground, std::shared_ptr<const terrain::Dem> dem,
                             std::shared_ptr<const Raster<float>> pdm, std::optional<terrain::Body> body) {
  PlanningProblem p;
  // The rover climbs against its body's gravity.
  p.body = body ? *body : maps::bodyOfCrs(dem->z.geo.crsWkt);
  if (ground.coverageGrid) {
    p.world = coverage::worldFromDem(*dem, ground.cell, ground.traversal);
  } else {
    p.pdm = std::move(pdm);
  }
  p.dem = std::move(dem);  // the coverage start check reads the map itself
  return p;
}

PlanningProblem problemOnGrid(const coverage::WorldParams& world) {
  PlanningProblem p;
  p.world = coverage::generateWorld(world);
  return p;
}

std::vector<RoverStart> randomValidStarts(const Planner& planner, const PlanningProblem& problem,
                                          const ParamSet& params, int rovers, std::uint64_t seed) {
  PlanningProblem trial = problem;
  for (std::uint64_t k = 0;; ++k) {
    trial.rovers = coverage::cellsToStarts(problem.world.geometry(),
                                           coverage::randomStarts(problem.world, rovers, seed + k));
    try {
      planner.validate(trial, params);
      return trial.rovers;
    } catch (const Error& e) {
      if (k >= 20 || e.field().rfind("rovers", 0) != 0) return trial.rovers;  // validate says why
    }
  }
}

std::vector<RoverStart> formationStarts(const terrain::Dem& dem, const ParamSet& teamParams, int n) {
  const team::TeamPlannerParams typed = team::parseTeamParams(teamParams);
  const GridGeometry& g = dem.geometry();
  const Eigen::Vector2d centre(g.widthMetres() / 2, g.heightMetres() / 2);
  std::vector<RoverStart> starts;
  for (const auto& p : team::formationStarts(dem, typed.mission, centre, n))
    starts.push_back({{p.x, p.y}, p.heading});
  return starts;
}

Raster<float> randomPdm(const terrain::Dem& dem, int components, std::uint64_t seed) {
  const GridGeometry& g = dem.geometry();
  std::vector<std::uint8_t> valid(static_cast<std::size_t>(g.cellCount()));
  for (int i = 0; i < g.cellCount(); ++i) valid[static_cast<std::size_t>(i)] = !std::isnan(dem.z.at(i));
  Raster<float> p = pdm::discretise(pdm::randomGaussians(g, components, seed), g, valid);
  p.geo = dem.z.geo;
  return p;
}

}  // namespace rover::problems
