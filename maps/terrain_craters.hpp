#pragma once
// Impact features of the synthetic terrain (synthetic_terrain.cpp): craters with a power-law size
// distribution, rim and bowl profiles and degradation, and the rocks on the surface, clustered in
// the ejecta of fresh craters.
#include <cstdint>
#include <vector>

#include "maps/terrain_canvas.hpp"

namespace rover::maps::synthetic {

// Craters.
//
// Size-frequency: cumulative N(>D) = K·D^-2 per unit area (D and area in the same unit, so K is
// dimensionless). K ≈ 10^-1.1 ≈ 0.08 is the empirical equilibrium density of small lunar craters
// (Trask 1966; Gault 1970), reached on mare surfaces for D below ~100 m; the geometric saturation
// limit is K ≈ 1.54.
//
// Profile of a fresh simple crater (Pike 1977, lunar simple craters): rim-to-floor depth
// d ≈ 0.196·D, rim height above the surroundings h_r ≈ 0.036·D. The bowl is a paraboloid
// (the usual approximation of a simple crater's cross-section), h(r) = h_r − d·(1 − ρ²) for
// ρ = r/R ≤ 1, relative to the pre-impact surface. Outside, the ejecta blanket thins as h_r·ρ^-3
// (McGetchin, Settle & Head 1973), tapered to zero at ρ = kEjectaRadius. Large craters become
// complex and shallower: depth is capped by the complex-crater law (Pike 1977 for the Moon, d
// = 1.044·D^0.301 km; Garvin et al. 2003 for Mars, d ≈ 0.36·D^0.49 km).
//
// Degradation: most small craters are old and shallowed by diffusion (Fassett & Thomson 2014), so
// each crater gets a uniform age in [0, 1) and a freshness f = exp(−age/τ): diffusion shallows a
// bowl roughly exponentially in time (Fassett & Thomson 2014), and a small τ means that only the
// youngest few percent are still sharp, as in an equilibrium population. f scales d/D from
// kDegradedDepthRatio (f = 0) to the fresh value (f = 1). Craters are stamped oldest first; inside
// its bowl a crater replaces the older topography by its own bowl in proportion to its freshness
// (a fresh crater erases what was there, a degraded one only dents it), and outside it adds its
// ejecta.

struct CraterSpec {
  double density = 0.0;            // K
  double minCells = 4.0;           // smallest D in cells (a smaller bowl is not drawn by the grid)
  double minDiameter = 0.0;        // and in metres
  double maxDiameterFactor = 1.0;  // largest D = factor × site extent ...
  double maxDiameter = 2.0e5;      // ... and never above this (metres)
  // Above breakDiameter the cumulative law steepens to D^-largeSlope: the production population,
  // not yet in equilibrium (lunar maria: equilibrium up to a few hundred metres, production slope
  // about −3 above; Neukum, Ivanov & Hartmann 2001). Keeps a 10 km site from being all basin.
  double breakDiameter = 1.0e30;
  double largeSlope = 3.0;
  double freshnessTime = 0.2;  // τ, as a fraction of the oldest age: smaller = fewer fresh
  // Complex-crater depth d = a·D_km^b km, caps the simple-crater depth for large D.
  double complexDepthA = 1.044;
  double complexDepthB = 0.301;
};

struct Crater {
  double x = 0, y = 0;      // centre, local metres
  double radius = 0;        // R = D/2
  double depth = 0;         // d, rim crest to floor
  double rim = 0;           // h_r
  double freshness = 0;     // f in [0, 1]
  double age = 0;           // sort key, oldest first
  std::uint64_t order = 0;  // tie-break, keeps the sort deterministic
};

// The craters of the site (and of a margin around it, whose ejecta reach in), oldest first.
std::vector<Crater> sampleCraters(const Canvas& canvas, const CraterSpec& spec, double multiplier,
                                  std::uint64_t seed);
// Replaces the topography inside the crater's bowl in proportion to its freshness and adds its
// ejecta outside.
void stampCrater(Canvas& canvas, const Crater& c);

// Rocks: boulders of 0.2–1.5 m on the surface, cumulative N(>D) ∝ D^-2.5 as in the Surveyor and
// Apollo counts of lunar rocks (Shoemaker & Morris 1970; Cintala & McBride 1995), each a half
// ellipsoid about half as high as wide. A DEM cell holds the mean height over its area, so each
// rock is supersampled 4 × 4 per cell: a 0.2 m rock on a 0.25 m cell is a small bump, not a spike,
// and rocks smaller than a cell are not generated at all. Part of the rocks lie in the ejecta of
// the freshest craters, where blocks concentrate on real surfaces, so rocky patches cluster.

struct RockSpec {
  double density = 0.0;    // rocks per m² with D >= kRockMinDiameter
  double clustered = 0.5;  // fraction placed around fresh craters (when there are any)
};

// Scatters the rocks, part of them around the fresh `craters`.
void addRocks(Canvas& canvas, const RockSpec& spec, double multiplier, const std::vector<Crater>& craters,
              std::uint64_t seed);

}  // namespace rover::maps::synthetic
