#include "server/problems/problem_builder.hpp"

#include <cmath>

#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/pdm/pdm.hpp"
#include "maps/georef.hpp"

namespace rover::problems {

PlanningProblem problemOnMap(const MapGround& ground, std::shared_ptr<const terrain::Dem> dem,
                             std::shared_ptr<const Raster<float>> pdm, std::optional<terrain::Body> body) {
  PlanningProblem p;
  // The rover climbs against its body's gravity.
  p.body = body ? *body : maps::bodyOfCrs(dem->z.geo.crsWkt);
  if (ground.kind == Ground::CoverageGrid) {
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

Raster<float> randomPdm(const terrain::Dem& dem, int components, std::uint64_t seed) {
  const GridGeometry& g = dem.geometry();
  std::vector<std::uint8_t> valid(static_cast<std::size_t>(g.cellCount()));
  for (int i = 0; i < g.cellCount(); ++i) valid[static_cast<std::size_t>(i)] = !std::isnan(dem.z.at(i));
  Raster<float> p = pdm::discretise(pdm::randomGaussians(g, components, seed), g, valid);
  p.geo = dem.z.geo;
  return p;
}

Raster<float> uniformPdm(const terrain::Dem& dem, const std::vector<std::uint8_t>& inArea) {
  std::vector<std::uint8_t> valid = inArea;
  for (int i = 0; i < dem.geometry().cellCount(); ++i) valid[static_cast<std::size_t>(i)] &= !std::isnan(dem.z.at(i));
  Raster<float> p = pdm::normaliseWeights(Raster<float>(dem.geometry(), 1.0f), valid);
  p.geo = dem.z.geo;
  return p;
}

}  // namespace rover::problems
