#pragma once
// Team-wide route search over a probability distribution map (SPEC §3.1, paper 001 §3.5):
// LHC_GW_CONV after Lin & Goodrich (2009) — local hill climbing (LHC) over footprint-sized search
// cells, ties broken by a 3×3 box blur (eq. 6–7), repeated over "global warming" levels (eq. 8) —
// and a boustrophedon (lawnmower) baseline for comparison. Pure, deterministic, no I/O.
//
// Choices made here where the paper is silent (each is repeated where it is implemented):
// - Search cells are squares of the footprint anchored at the map's lower-left (south-west)
//   corner, the origin of the local frame, so search-cell centres and map positions share one
//   frame. When the map is not a whole number of footprints, the northern row and eastern column
//   are partial; their centre is the centre of the part inside the map.
// - A map cell belongs to the search cell containing the map cell's centre.
// - A search cell is impassable (never a target) when strictly more than half of its map cells are
//   Impassable or NoData (exactly 50 % stays passable), or when it holds no map cell at all.
// - The start cell counts as visited: its original mass is part of every route's score and of the
//   accumulated-probability curve at distance 0 (the team searches the footprint it stands in). It
//   may be impassable (the team may be set down there); it is never a *target* then.
#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/grid/raster.hpp"

namespace rover::team {

// The search cell (of `searchGrid`, squares of `footprint` metres anchored at the map's south-west
// corner) holding the local position `p`, clamped into the grid: the one position → search-cell
// function of the team planner (the grid's own cells, the team's start, the replay).
CellIndex searchCellAt(const GridGeometry& searchGrid, double footprint, const Eigen::Vector2d& p);

struct SearchGrid {
  // Original PDM mass per search cell (sum of the masses of the map cells whose centre lies in
  // it), for every cell, impassable ones included. geometry: rows, cols, cellWidth = cellHeight =
  // the footprint in metres.
  Raster<double> mass;
  // 1 = impassable (never a target), 0 = passable. Same geometry as `mass`.
  Raster<std::uint8_t> impassable;
  double footprint = 5.0;  // metres, the side of a search cell
  double mapWidth = 0;     // metres, extent of the source map (x, east)
  double mapHeight = 0;    // metres (y, north)

  const GridGeometry& geometry() const { return mass.geometry; }
  int rows() const { return mass.geometry.rows; }
  int cols() const { return mass.geometry.cols; }
  double cellSize() const { return footprint; }
  bool passable(CellIndex c) const { return impassable(c.row, c.col) == 0; }
  // Centre of a search cell in the local frame (SPEC §0: x east, y north, metres from the map's
  // south-west corner); for a partial edge cell, the centre of its part inside the map.
  Eigen::Vector2d centre(CellIndex c) const;
  // The search cell holding a position (searchCellAt).
  CellIndex cellAt(const Eigen::Vector2d& p) const { return searchCellAt(geometry(), footprint, p); }
  // Total mass over passable cells.
  double passableMass() const;
};

// Splits the map into footprint-sized search cells (default 5 m: a 150 m site gives 30 × 30).
// `classes` holds terrain::TerrainClass values on the PDM's grid; an empty raster means every
// map cell is passable. Throws InvalidParameter "footprint_m" unless the footprint is finite and
// at least the map's larger cell side (so every full search cell holds a map cell), InvalidInput
// "pdm" for an empty PDM or a negative/non-finite mass, InvalidInput "classes" when its grid
// differs from the PDM's.
SearchGrid makeSearchGrid(const Raster<float>& pdmMass, const Raster<std::uint8_t>& classes,
                          double footprintM = 5.0);

struct RouteParams {
  int targets = 64;            // route length: number of target cells after the start
  int warmingLevels = 20;      // l of eq. 8; C = p_max / l. 0 = no warming (k = 0 only)
  bool globalWarming = true;   // false: plain LHC (k = 0 only)
  bool convolutionTieBreak = true;  // false: ties go straight to the fixed neighbour order
};
// Throws InvalidParameter naming "targets" ([1, 100000]) or "warming_levels" ([0, 1000]).
void validateRouteParams(const RouteParams& p);

struct Route {
  CellIndex start;
  Eigen::Vector2d startCentre{0, 0};     // local frame
  std::vector<CellIndex> cells;          // the targets, in order (the start excluded)
  std::vector<Eigen::Vector2d> centres;  // their centres in the local frame
  // Original mass of the distinct cells of {start} ∪ cells.
  double score = 0;
  int distinctCells = 0;  // distinct cells of {start} ∪ cells
  int warmingLevel = 0;   // the k that won (0 for plain LHC and the lawnmower)
  std::vector<double> levelScores;  // score of the path found at each k = 0..l (LHC only)
};

// LHC_GW_CONV (paper 001 §3.5, Lin & Goodrich 2009). From `start`, `params.targets` times: move
// to the passable 8-neighbour with the highest working value; ties (exact equality) are broken by
// the neighbour's 3×3 box-blur value, remaining ties by the fixed order E, NE, N, NW, W, SW, S, SE.
// A visited cell's working value is 0 (it is "completely seen"); revisits are allowed but only
// happen when every passable neighbour's working value is 0. With no passable neighbour, the best passable cell at
// Chebyshev distance 2 is taken (same ordering, then row-major order); with none there either, the
// route ends there, shorter than `targets` (a walled-in start never becomes a target). Global warming runs the climb for k = 0..l on
// p_k = max(p − k·C, 0), C = p_max / l (p_max over passable cells); each path is scored on the
// ORIGINAL mass of its distinct cells; the best wins, ties to the smallest k.
// Known limitation kept from the paper: when every neighbour and every neighbour's 3×3 window is
// 0 (a dead end with nothing left within two cells), the fixed order decides and the climb can
// oscillate between two cells until the targets run out.
// Cost: O(targets · (l + 1) · 9 · 9) after one O(cells) allocation — no per-k copy of the grid.
// Throws InvalidParameter (validateRouteParams) and InvalidInput "start" outside the grid.
Route lhcGwConv(const SearchGrid& grid, CellIndex start, const RouteParams& params = {});

// Boustrophedon baseline: lanes are rows; a row r runs east when |r − start row| is even, west
// when odd. Order: the start row from the start to the east edge; the rows below it down to the
// bottom row; the rows above it from start row − 1 up to row 0; last the west part of the start
// row (start col − 1 down to 0, westward). Impassable cells and the start are
// skipped; the route stops after `targets` targets or when every cell has been listed (so it may
// be shorter). Scored like lhcGwConv. Throws InvalidParameter "targets", InvalidInput "start".
Route lawnmower(const SearchGrid& grid, CellIndex start, int targets);

// A route through `cells` in order from `start`, with its centres, score and distinct cells (the
// shared ending of every route method). Throws InvalidInput "start" outside the grid.
Route scoredRoute(const SearchGrid& grid, CellIndex start, std::vector<CellIndex> cells);

// Accumulated probability vs distance: one point for the start (0 m, its mass) and one per
// target: (distance in metres along the straight segments between successive centres, original
// mass of the distinct cells seen so far). The last value equals route.score.
std::vector<std::pair<double, double>> accumulatedAlongRoute(const SearchGrid& grid,
                                                             const Route& route);

}  // namespace rover::team
