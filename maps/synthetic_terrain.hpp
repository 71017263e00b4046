#pragma once
// Synthetic terrain for the embedded default map and for tests (issue: terrain layers): `moon`
// (craters with a power-law size distribution, rim and bowl profiles, scattered rocks) and `mars`
// (rolling relief, dunes or ridges, a few craters). Deterministic for a seed. The result is
// georeferenced: lower-left corner at (0, 0) in an equirectangular CRS on the body's IAU sphere.
#include <cstdint>
#include <string>

#include "core/terrain/dem.hpp"

namespace rover::maps {

struct SyntheticTerrainParams {
  std::string preset = "mars";  // moon | mars
  int size = 600;               // cells per side
  double cellSize = 0.25;       // metres
  std::uint64_t seed = 1;
  // Multipliers on the preset's own defaults (documented in synthetic_terrain.cpp), each in
  // [0, 10]; 1 keeps the preset as tuned, 0 removes the feature.
  double craterDensity = 1.0;  // craters per area (error field "crater_density")
  double rockDensity = 1.0;    // rocks per area ("rock_density")
  double relief = 1.0;         // amplitude of the rolling relief and of the ridges ("relief")
};

// Throws rover::Error (InvalidParameter naming preset/size/cell/crater_density/rock_density/
// relief) on bad parameters.
terrain::Dem generateTerrain(const SyntheticTerrainParams& params);

// WKT of an equirectangular projection on the IAU sphere of "moon" (R = 1737400 m) or
// "mars" (R = 3396190 m). Throws InvalidParameter (field "body") for any other name.
std::string bodyCrsWkt(const std::string& body);

}  // namespace rover::maps
