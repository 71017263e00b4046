#include "maps/synthetic_terrain.hpp"

#include <cpl_conv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "maps/terrain_craters.hpp"
#include "maps/terrain_relief.hpp"

// How the terrain is built, and why.
//
// Everything is laid out in the local frame (x east, y north, metres from the lower-left corner,
// SPEC §0) at cell centres, so a feature is the same physical object whatever the grid. Features
// are added in geological order: rolling relief (and, on Mars, a ridge field) first, then craters
// from oldest to youngest, each young crater erasing what lay inside its bowl, then loose rocks on
// top. All randomness comes from rover::Rng streams derived from the one seed (core/common/
// random.hpp), never from std:: distributions, so a seed gives the same heights on every standard
// library; the libm functions used (pow, sqrt, exp, cos, sin) give the same bits on one build.
//
// Scale. Relief is fractal (amplitude ∝ wavelength^H with H < 1, so slopes fall gently with
// baseline, as measured on planetary DTMs); craters follow a cumulative power law N(>D) ∝ D^-2,
// which is itself scale-free. Both are cut at the small end where the grid can no longer draw them
// (a few cells), so a coarse grid of a large site shows the same slope statistics as a fine grid of
// a small one, and a large site simply holds more and bigger craters. Rocks have a physical size
// (0.2–1.5 m); those smaller than a cell are left out, so on a 10 m grid there are none.
//
// Tuning target (SPEC §2, paper 001 §3.4 classes on the worst 8-neighbour slope): on the defaults
// (600 × 600 cells of 0.25 m) roughly 80–95 % traversable (< 10°), 3–15 % high risk and 1–8 %
// impassable (≥ 15°); their Jezero site had 89.5 / 8.4 / 2.1 %. The impassable share sits in
// crater walls, ridge crests and rocks rather than everywhere.
// tests/maps/test_synthetic_terrain.cpp checks those ranges.

namespace rover::maps {

using namespace synthetic;  // the generators

namespace {

// Sub-seed streams (rover::deriveSeed), one per feature, so changing one never shifts another.
enum Stream : std::uint64_t { kReliefStream = 1, kRidgeStream, kCraterStream, kRockStream };

// ----------------------------------------------------------------------------------------------
// Presets. The numbers were tuned against the class shares above (see the file header).

struct Recipe {
  ReliefSpec relief;
  RidgeSpec ridges;
  CraterSpec craters;
  RockSpec rocks;
};

Recipe moonRecipe() {
  Recipe r;
  // Gentle undulation of the mare plains.
  r.relief = {.slope = 0.035,
              .hurst = 0.8,
              .referenceWavelength = 10.0,
              .maxWavelengthFactor = 1.0,
              .minWavelength = 2.0};
  // Equilibrium cratering, mostly degraded.
  r.craters.density = 0.08;
  r.craters.minCells = 4.0;
  r.craters.minDiameter = 0.0;
  r.craters.maxDiameterFactor = 1.0;
  r.craters.freshnessTime = 0.08;
  r.craters.breakDiameter = 250.0;
  r.craters.largeSlope = 3.2;
  r.rocks = {.density = 0.05, .clustered = 0.6};
  return r;
}

Recipe marsRecipe() {
  Recipe r;
  r.relief = {.slope = 0.05,
              .hurst = 0.75,
              .referenceWavelength = 10.0,
              .maxWavelengthFactor = 1.0,
              .minWavelength = 2.0,
              .roughGain = 8.0,
              .roughOctaves = 2,
              .patchWavelength = 40.0,
              .patchThreshold = 0.15,
              .patchRamp = 0.3};
  r.ridges.enabled = true;
  // A few craters: far below lunar equilibrium, no small ones.
  r.craters.density = 0.01;
  r.craters.minCells = 8.0;
  r.craters.minDiameter = 3.0;
  r.craters.maxDiameterFactor = 0.7;
  r.craters.freshnessTime = 0.3;
  r.craters.complexDepthA = 0.36;
  r.craters.complexDepthB = 0.49;
  r.rocks = {.density = 0.01, .clustered = 0.5};
  return r;
}

void validate(const SyntheticTerrainParams& p) {
  if (p.preset != "moon" && p.preset != "mars")
    throwInvalidParameter("preset", "must be moon or mars, not \"" + p.preset + "\"");
  if (p.size < 16 || p.size > 16384) throwInvalidParameter("size", "must be in [16, 16384] cells");
  if (!(std::isfinite(p.cellSize) && p.cellSize > 0 && p.cellSize <= 1000))
    throwInvalidParameter("cell", "must be a number of metres in (0, 1000]");
  auto multiplier = [](double v, const char* field) {
    if (!(v >= 0 && v <= 10)) throwInvalidParameter(field, "must be a multiplier in [0, 10]");
  };
  multiplier(p.craterDensity, "crater_density");
  multiplier(p.rockDensity, "rock_density");
  multiplier(p.relief, "relief");
}

}  // namespace

terrain::Dem generateTerrain(const SyntheticTerrainParams& params) {
  validate(params);
  const GridGeometry geometry{params.size, params.size, params.cellSize, params.cellSize};
  terrain::Dem dem;
  dem.z = Raster<float>(geometry, 0.0f);
  Canvas canvas{dem.z.values, params.size, params.cellSize};
  const Recipe recipe = params.preset == "moon" ? moonRecipe() : marsRecipe();

  addRelief(canvas, recipe.relief, params.relief, deriveSeed(params.seed, kReliefStream));
  addRidges(canvas, recipe.ridges, params.relief, deriveSeed(params.seed, kRidgeStream));
  const auto craters = sampleCraters(canvas, recipe.craters, params.craterDensity,
                                     deriveSeed(params.seed, kCraterStream));
  for (const auto& c : craters) stampCrater(canvas, c);
  addRocks(canvas, recipe.rocks, params.rockDensity, craters, deriveSeed(params.seed, kRockStream));

  const double extent = params.size * params.cellSize;
  dem.z.geo.valid = true;
  dem.z.geo.geotransform = {0.0, params.cellSize, 0.0, extent, 0.0, -params.cellSize};
  dem.z.geo.crsWkt = bodyCrsWkt(params.preset);
  return dem;
}

std::string bodyCrsWkt(const std::string& body) {
  // IAU mean radii (Archinal et al. 2018): spheres, as the PDS products for these bodies use.
  double radius = 0;
  std::string name;
  if (body == "moon") {
    radius = 1737400.0;
    name = "Moon";
  } else if (body == "mars") {
    radius = 3396190.0;
    name = "Mars";
  } else {
    throwInvalidParameter("body", "must be moon or mars, not \"" + body + "\"");
  }
  OGRSpatialReference srs;
  srs.SetProjCS((name + " Equirectangular").c_str());
  // Inverse flattening 0 = a sphere.
  srs.SetGeogCS(("GCS_" + name).c_str(), ("D_" + name).c_str(), name.c_str(), radius, 0.0,
                "Reference_Meridian", 0.0);
  srs.SetEquirectangular2(0.0, 0.0, 0.0, 0.0, 0.0);
  srs.SetLinearUnits(SRS_UL_METER, 1.0);
  char* wkt = nullptr;
  if (srs.exportToWkt(&wkt) != OGRERR_NONE || wkt == nullptr) {
    CPLFree(wkt);
    throw Error(ErrorCode::InvalidInput, "body", "could not build the CRS of " + name);
  }
  std::string result(wkt);
  CPLFree(wkt);
  return result;
}

}  // namespace rover::maps
