#pragma once
// A coverage world from a DEM (paper 000 §III.B, SPEC §1/§2, issue 11).
//
// The coverage grid is laid in the map's local frame (SPEC §0): square cells of `cell` metres
// from the south-west corner, whatever the DEM's pixel shape (HiRISE's 0.9967 × 1 m after the
// cos φ correction, a geographic raster's per-row spacing, a projected grid). A strip narrower
// than one cell along the north and east edges is left out. Each DEM pixel belongs to the coverage
// cell holding its centre; a coverage cell smaller than a pixel takes the pixel under its centre.
// A coverage cell is an obstacle when any of its pixels is impassable (the worst slope across it,
// SPEC §2) or has no data, or when the slope from its height to a neighbour's is impassable on the
// coverage grid itself; its height, which feeds the β·|Δh| cost, energy and pitch, is the mean of
// its pixels (bilinear at the centre when it has none of its own). So no move between free cells
// pitches at the impassable slope or more.
//
// The local frame is metric at the map's centre row: on a geographic or equirectangular map far
// from its centre latitude, ground distances differ from it by cos φ / cos φ_centre.
#include <cstdint>

#include "core/coverage/world.hpp"
#include "core/terrain/layers.hpp"

namespace rover::coverage {

// The most cells a DEM's coverage grid may hold, whatever the user asks: ~40 bytes a cell for the
// grid and the planner's maps, and a paper-mode run may use its whole step budget of 20 moves a
// cell (on a DEM whose obstacle interiors are never sensed), so a path of up to 20 million moves.
constexpr std::int64_t kMaxCoverageCells = 1'000'000;

// The coverage grid over a map of geometry `map` with cells of `cell` metres (no checks).
GridGeometry coverageGrid(const GridGeometry& map, double cell);
// The map's own cell as a coverage cell: the longer pixel side (HiRISE 0.9967 × 1 m -> 1 m), so
// every coverage cell holds at least one pixel centre.
double nativeCoverageCell(const GridGeometry& map);
// The default coverage cell: the native cell, or the smallest 3-significant-digit size whose
// grid holds at most `cellBudget` cells.
double defaultCoverageCell(const GridGeometry& map, std::int64_t cellBudget);
// `cell` <= 0 means the default (within `cellBudget`). Throws InvalidParameter("coverage_cell")
// when the grid would be smaller than 2 × 2 cells or hold more than kMaxCoverageCells (saying
// which size fits).
double resolveCoverageCell(const GridGeometry& map, double cell, std::int64_t cellBudget);

World worldFromDem(const terrain::Dem& dem, double cell,
                   const terrain::TraversabilityParams& params = {});
// On the DEM's own cells; they must be square (the grid tests' shorthand).
World worldFromDem(const terrain::Dem& dem, const terrain::TraversabilityParams& params = {});

}  // namespace rover::coverage
