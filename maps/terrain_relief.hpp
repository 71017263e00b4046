#pragma once
// Relief generators of the synthetic terrain (synthetic_terrain.cpp): rolling fractal relief from
// octaves of gradient noise, and the Mars ridge field.
#include <cstdint>

#include "maps/terrain_canvas.hpp"

namespace rover::maps::synthetic {

// Rolling relief: fractional Brownian motion from octaves of gradient noise. An octave of
// wavelength λ gets amplitude A(λ) = s·λ/(2π)·(λ/λref)^(H−1): its slopes are ~s at λref and fall
// as λ^(H−1) at longer wavelengths (H ≈ 0.7–0.9 for planetary surfaces at metre to km baselines,
// e.g. Kreslavsky & Head 2000 for Mars, Rosenburg et al. 2011 for the Moon).

struct ReliefSpec {
  double slope = 0.0;                 // s, dimensionless, at the reference wavelength
  double hurst = 0.8;                 // H
  double referenceWavelength = 10.0;  // λref, metres
  double maxWavelengthFactor = 1.0;   // longest octave = factor × site extent
  double minWavelength = 1.0;         // metres; never below kMinNoiseCells cells either
  // Rough patches (outcrops, blocky ground among smooth regolith): the shortest `roughOctaves`
  // octaves get their amplitude multiplied by 1 + roughGain·mask, mask a smoothstep of a noise of
  // wavelength patchWavelength (at least 6× the roughest octave) between patchThreshold and
  // patchThreshold + patchRamp. They hold the high-risk ground in patches, not everywhere.
  double roughGain = 0.0;
  int roughOctaves = 2;
  double patchWavelength = 40.0;
  double patchThreshold = 0.2;
  double patchRamp = 0.3;
};

// Adds the relief (`multiplier` scales its amplitude; 0 adds none).
void addRelief(Canvas& canvas, const ReliefSpec& spec, double multiplier, std::uint64_t seed);

// Ridge field (Mars): parallel, sharp-crested ridges like the transverse aeolian ridges and
// megaripples of Jezero and Gale — wavelengths of ~10 m, heights of a metre or less, a steeper lee
// side. The cross-section over one wavelength rises as u^γ on each side of the crest (u = 0 in the
// trough, 1 at the crest): flat troughs and steep flanks only near the crest, so the impassable
// cells form thin lines along the crests instead of whole flanks. The crest lines wander (phase
// noise), the height varies along them, and the field covers only part of the site (a smooth
// noise mask), as dune fields do.

struct RidgeSpec {
  bool enabled = false;
  double minWavelength = 8.0;     // metres, drawn uniformly in [min, max] ...
  double maxWavelength = 14.0;    // ... and never below kMinRidgeCells cells
  double aspect = 0.04;           // crest height / wavelength
  int sharpness = 3;              // γ (an integer: u^γ by multiplication)
  double waviness = 0.35;         // crest displacement amplitude, in wavelengths
  double coverThreshold = -0.15;  // mask noise level where the field starts ...
  double coverRamp = 0.35;        // ... and the width of its ramp to full height
};

// Adds the ridge field where spec.enabled (`multiplier` scales the heights).
void addRidges(Canvas& canvas, const RidgeSpec& spec, double multiplier, std::uint64_t seed);

}  // namespace rover::maps::synthetic
