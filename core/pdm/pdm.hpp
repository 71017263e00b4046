#pragma once
// Probability distribution maps: where the science is likely to be (paper 001 eq. 5, SPEC §2).
// p(x) = Σ_i w_i N(x; μ_i, Σ_i) / Σ_i w_i — with equal weights exactly the paper's
// (1/G) Σ_{i=1..G} N(x; μ_i, Σ_i). Discretised as probability *mass* per cell, normalised so the
// valid cells of the map sum to 1.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/grid/raster.hpp"

namespace rover::pdm {

struct Gaussian {
  Eigen::Vector2d mean{0, 0};  // local frame, metres
  double sigmaX = 1.0;         // metres, along the component's own x axis
  double sigmaY = 1.0;         // metres, along its y axis
  double rotation = 0.0;       // radians counter-clockwise from east, of the sigmaX axis
  double weight = 1.0;         // relative; >= 0
};

// At most this many components per PDM: discretising costs up to one window of cells per
// component (see discretise), so the count bounds the work.
inline constexpr std::size_t kMaxComponents = 256;

// Throws InvalidParameter naming "components[i].field" (x, y, sigma_x, sigma_y, rotation_deg,
// weight) for a bad component, an empty list or more than kMaxComponents.
void validateGaussians(const std::vector<Gaussian>& components);
// The same, plus bounds relative to the map `g` (so every later step stays in range): a mean at
// most one map diagonal outside the map; sigmas in [cell / 1000, 100 × diagonal]; weights
// <= 1e9.
void validateGaussians(const std::vector<Gaussian>& components, const GridGeometry& g);

// Mixture density at a local point (per square metre).
double density(const std::vector<Gaussian>& components, const Eigen::Vector2d& xy);

// Probability mass per cell of the mixture (paper 001 eq. 5). Each component is integrated over
// ±6σ around its mean by sampling every cell on an s×s sub-grid (s grows when σ is small against
// the cell, so narrow peaks are not missed between cell centres). Only cells that meet the
// component's kWindowSigmas-σ (10σ) ellipse (Mahalanobis distance) are visited, so a long thin
// component costs its own area, not its bounding box: the work is at most
// Σ_components (cells in its window) × s², with s <= 16. The samples left out have
// exp(-q/2) <= exp(-50) ≈ 2e-22 of the component's peak; for a round component the ±6σ box lies
// inside the 10σ circle, so nothing changes. Cells with valid[i] == 0 (nodata) get 0;
// `valid` empty = all. Validates against `g` (above). Throws InvalidInput if no mass falls on
// valid cells of the map.
inline constexpr double kWindowSigmas = 10.0;
// The work one PDM may cost (density evaluations: Σ cells in each window × s²), so a request's
// time is bounded whatever its components: about 5–10 s on one core. A few wide components on
// a 50 M-cell map fit; 256 components each as wide as the map do not (InvalidParameter
// "components" from discretise, before any work).
inline constexpr double kMaxDiscretisationSamples = 1e9;
double discretisationCost(const std::vector<Gaussian>& components, const GridGeometry& g);
Raster<float> discretise(const std::vector<Gaussian>& components, const GridGeometry& g,
                         const std::vector<std::uint8_t>& valid = {});

// The mixture's mass on a window of `map` (a mission area's planning window, core/planning/
// mission_area.hpp) whose lower-left corner lies at `origin` in the map's frame, normalised over
// the window's valid cells: the same masses as discretise on the map, restricted to the window and
// scaled to sum 1 (the components' weights are relative, so leaving out those whose 10σ ellipse
// misses the window changes nothing). Validates against `map`; the work follows the window.
Raster<float> discretiseOnWindow(const std::vector<Gaussian>& components, const GridGeometry& map,
                                 const GridGeometry& window, const Eigen::Vector2d& origin,
                                 const std::vector<std::uint8_t>& valid = {});

// G random components (paper 001 §4: G = 4): means uniform over the map, σ uniform in
// [5 %, 20 %] of the shorter side, rotation uniform, equal weights. Seeded.
std::vector<Gaussian> randomGaussians(const GridGeometry& g, int count, std::uint64_t seed);

// A PDM given as a raster of non-negative weights on the map's grid: normalised to mass per
// cell. NaN cells and invalid map cells get 0. Throws InvalidInput on negative or infinite
// values or a zero total.
Raster<float> normaliseWeights(const Raster<float>& weights, const std::vector<std::uint8_t>& valid = {});

}  // namespace rover::pdm
