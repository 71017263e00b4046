#include "core/team/route_search.hpp"

#include <algorithm>
#include <optional>
#include <cmath>
#include <string>

#include "core/common/error.hpp"
#include "core/grid/neighbours.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

namespace {

constexpr int kMaxTargets = 100000;
constexpr int kMaxWarmingLevels = 1000;

void checkStart(const SearchGrid& grid, CellIndex start) {
  if (grid.geometry().cellCount() == 0)
    throw Error(ErrorCode::InvalidInput, "grid", "the search grid is empty");
  if (!grid.geometry().contains(start))
    throw Error(ErrorCode::InvalidInput, "start",
                "start cell (" + std::to_string(start.row) + ", " + std::to_string(start.col) +
                    ") is outside the " + std::to_string(grid.rows()) + " x " +
                    std::to_string(grid.cols()) + " search grid");
}

void checkTargets(int targets) {
  if (targets < 1 || targets > kMaxTargets)
    throwInvalidParameter("targets", "must be in [1, " + std::to_string(kMaxTargets) + "]");
}

// Number of footprint-sized cells along an extent; the tolerance keeps 150 m / 5 m at 30 when the
// extent carries rounding noise (600 · 0.25 m).
int cellsAlong(double extent, double footprint) {
  return std::max(1, static_cast<int>(std::ceil(extent / footprint - 1e-9)));
}

// One hill climb on the lazily held working copy of p_k (eq. 8) — no per-k copy of the grid:
//   working(x) = 0                       if x was visited in this climb ("completely seen"),
//              = max(p(x) − offset, 0)   otherwise (offset = k·C).
// `seen` is a caller-owned flag per cell, all 0 on entry and reset to 0 before returning.
class Climb {
 public:
  Climb(const SearchGrid& grid, double offset, bool convolution, std::vector<std::uint8_t>& seen)
      : grid_(grid), g_(grid.geometry()), offset_(offset), convolution_(convolution), seen_(seen) {}

  std::vector<CellIndex> run(CellIndex start, int targets) {
    std::vector<CellIndex> path;
    path.reserve(static_cast<std::size_t>(targets));
    // The paper zeroes the cell just left. We zero a cell on arrival instead: the current cell is
    // never a candidate for itself, and it lies in the 3×3 window of all 8 neighbours alike, so the
    // choice among them is the same.
    seen_[g_.index(start)] = 1;
    CellIndex cur = start;
    for (int t = 0; t < targets; ++t) {
      const std::optional<CellIndex> next = chooseNext(cur);
      if (!next) break;  // walled in: the route ends here (the start never becomes a target)
      path.push_back(*next);
      seen_[g_.index(*next)] = 1;
      cur = *next;
    }
    seen_[g_.index(start)] = 0;
    for (const CellIndex& c : path) seen_[g_.index(c)] = 0;
    return path;
  }

 private:
  // Working value; 0 outside the grid and on impassable cells (the blur's padding, see below).
  double value(int row, int col) const {
    if (!g_.contains(row, col)) return 0.0;
    const int i = g_.index(row, col);
    if (grid_.impassable.at(i) != 0 || seen_[i] != 0) return 0.0;
    return std::max(grid_.mass.at(i) - offset_, 0.0);
  }

  // Eq. 6–7: the 3×3 normalised box blur of the working copy at (row, col). Border: cells outside
  // the grid count as 0 and the divisor stays 9 (zero padding). Impassable cells count as 0 too:
  // their mass can never be collected, so it must not pull the route toward them. Evaluated on
  // demand (9 reads) and only for tied candidates, from the current working copy, so zeroing a
  // cell needs no update and no drift accumulates. The constant 1/9 does not change the order, so
  // the window sums are compared directly.
  double blurSum(int row, int col) const {
    double s = 0.0;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) s += value(row + dr, col + dc);
    return s;
  }

  struct Best {
    bool found = false;
    CellIndex cell;
    double value = 0;
    bool blurKnown = false;
    double blur = 0;
  };

  // Candidates are offered in a fixed order; a later one wins only if strictly better in value,
  // or equal in value and strictly better in blur (ties beyond that keep the earlier one).
  void offer(Best& best, int row, int col) const {
    if (!g_.contains(row, col) || grid_.impassable(row, col) != 0) return;
    const double v = value(row, col);
    if (!best.found || v > best.value) {
      best = Best{true, CellIndex{row, col}, v, false, 0.0};
      return;
    }
    if (v < best.value || !convolution_) return;
    if (!best.blurKnown) {
      best.blur = blurSum(best.cell.row, best.cell.col);
      best.blurKnown = true;
    }
    const double b = blurSum(row, col);
    if (b > best.blur) best = Best{true, CellIndex{row, col}, v, true, b};
  }

  std::optional<CellIndex> chooseNext(CellIndex cur) const {
    Best best;
    // The 8 neighbours in the fixed order E, NE, N, NW, W, SW, S, SE (core/grid/direction.hpp).
    for (const Neighbour& n : neighbours8(g_, cur)) offer(best, n.row, n.col);
    if (best.found) return best.cell;
    // No passable neighbour: the best passable cell at Chebyshev distance 2, offered in row-major
    // order (north-west first). The RRT of §3.2 finds the way round the impassable ring.
    for (int dr = -2; dr <= 2; ++dr)
      for (int dc = -2; dc <= 2; ++dc)
        if (std::max(std::abs(dr), std::abs(dc)) == 2) offer(best, cur.row + dr, cur.col + dc);
    if (best.found) return best.cell;
    return std::nullopt;  // walled in
  }

  const SearchGrid& grid_;
  const GridGeometry& g_;
  double offset_;
  bool convolution_;
  std::vector<std::uint8_t>& seen_;
};

// Original mass of the distinct cells of {start} ∪ cells, summed in first-visit order (the same
// order accumulatedAlongRoute uses, so its last value equals the score exactly). `mark` is a
// caller-owned flag per cell, all 0 on entry and on return.
double scorePath(const SearchGrid& grid, CellIndex start, const std::vector<CellIndex>& cells,
                 std::vector<std::uint8_t>& mark, int* distinct) {
  const GridGeometry& g = grid.geometry();
  double score = grid.mass(start.row, start.col);
  int count = 1;
  mark[g.index(start)] = 1;
  for (const CellIndex& c : cells) {
    const int i = g.index(c);
    if (mark[i] == 0) {
      mark[i] = 1;
      score += grid.mass.at(i);
      ++count;
    }
  }
  mark[g.index(start)] = 0;
  for (const CellIndex& c : cells) mark[g.index(c)] = 0;
  if (distinct != nullptr) *distinct = count;
  return score;
}

Route makeRoute(const SearchGrid& grid, CellIndex start, std::vector<CellIndex> cells) {
  Route r;
  r.start = start;
  r.startCentre = grid.centre(start);
  r.cells = std::move(cells);
  r.centres.reserve(r.cells.size());
  for (const CellIndex& c : r.cells) r.centres.push_back(grid.centre(c));
  return r;
}

}  // namespace

CellIndex searchCellAt(const GridGeometry& g, double footprint, const Eigen::Vector2d& p) {
  const int col = std::clamp(static_cast<int>(std::floor(p.x() / footprint)), 0, g.cols - 1);
  const int fromBottom = std::clamp(static_cast<int>(std::floor(p.y() / footprint)), 0, g.rows - 1);
  return {g.rows - 1 - fromBottom, col};
}

Eigen::Vector2d SearchGrid::centre(CellIndex c) const {
  Eigen::Vector2d p = cellToLocal(geometry(), c);
  // Partial cells on the north row / east column: the centre of the part inside the map.
  const double x0 = c.col * footprint;
  const double y0 = (rows() - 1 - c.row) * footprint;
  if (x0 + footprint > mapWidth) p.x() = 0.5 * (x0 + mapWidth);
  if (y0 + footprint > mapHeight) p.y() = 0.5 * (y0 + mapHeight);
  return p;
}

double SearchGrid::passableMass() const {
  double s = 0.0;
  for (int i = 0; i < geometry().cellCount(); ++i)
    if (impassable.at(i) == 0) s += mass.at(i);
  return s;
}

SearchGrid makeSearchGrid(const Raster<float>& pdmMass, const Raster<std::uint8_t>& classes,
                          double footprintM) {
  const GridGeometry& mg = pdmMass.geometry;
  if (pdmMass.empty()) throw Error(ErrorCode::InvalidInput, "pdm", "the PDM is empty");
  const double largerSide = std::max(mg.cellWidth, mg.cellHeight);
  if (!std::isfinite(footprintM) || !(footprintM >= largerSide * (1.0 - 1e-9)))
    throwInvalidParameter("footprint_m", "must be a finite number of metres >= the map cell size (" +
                                             std::to_string(largerSide) + " m)");
  if (!classes.empty() && (classes.geometry.rows != mg.rows || classes.geometry.cols != mg.cols))
    throw Error(ErrorCode::InvalidInput, "classes",
                "the terrain classes raster must have the PDM's rows and columns");

  SearchGrid sg;
  sg.footprint = footprintM;
  sg.mapWidth = mg.widthMetres();
  sg.mapHeight = mg.heightMetres();
  // Anchored at the local origin (south-west corner): search cell (r, c) covers
  // x ∈ [c·f, (c+1)·f), y ∈ [(rows−1−r)·f, (rows−r)·f); partial cells lie on the north and east.
  GridGeometry sgeo{cellsAlong(sg.mapHeight, footprintM), cellsAlong(sg.mapWidth, footprintM),
                    footprintM, footprintM};
  sg.mass = Raster<double>(sgeo, 0.0);
  sg.impassable = Raster<std::uint8_t>(sgeo, 0);

  std::vector<std::int64_t> total(static_cast<std::size_t>(sgeo.cellCount()), 0);
  std::vector<std::int64_t> blocked(total.size(), 0);
  const auto impassableClass = static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  for (int r = 0; r < mg.rows; ++r) {
    for (int c = 0; c < mg.cols; ++c) {
      const double v = pdmMass(r, c);
      if (!std::isfinite(v) || v < 0)
        throw Error(ErrorCode::InvalidInput, "pdm", "PDM masses must be finite and >= 0");
      // The map cell goes to the search cell holding its centre.
      const CellIndex sc = searchCellAt(sgeo, footprintM, cellToLocal(mg, {r, c}));
      const int si = sgeo.index(sc.row, sc.col);
      sg.mass.at(si) += v;
      ++total[static_cast<std::size_t>(si)];
      // Impassable and NoData (and any larger, unknown code) block the map cell.
      if (!classes.empty() && classes(r, c) >= impassableClass) ++blocked[static_cast<std::size_t>(si)];
    }
  }
  // Majority rule: impassable when strictly more than half of the map cells are blocked (exactly
  // half stays passable: the team can still search the other half), or when the cell holds no map
  // cell at all (a sliver at the north/east edge).
  for (int i = 0; i < sgeo.cellCount(); ++i) {
    const auto n = total[static_cast<std::size_t>(i)];
    sg.impassable.at(i) = (n == 0 || 2 * blocked[static_cast<std::size_t>(i)] > n) ? 1 : 0;
  }
  return sg;
}

void validateRouteParams(const RouteParams& p) {
  checkTargets(p.targets);
  if (p.warmingLevels < 0 || p.warmingLevels > kMaxWarmingLevels)
    throwInvalidParameter("warming_levels",
                          "must be in [0, " + std::to_string(kMaxWarmingLevels) + "]");
}

Route lhcGwConv(const SearchGrid& grid, CellIndex start, const RouteParams& params) {
  validateRouteParams(params);
  checkStart(grid, start);
  const GridGeometry& g = grid.geometry();

  double pMax = 0.0;  // global maximum over cells that can be targets
  for (int i = 0; i < g.cellCount(); ++i)
    if (grid.impassable.at(i) == 0) pMax = std::max(pMax, grid.mass.at(i));
  // l = 0 or a map without passable mass leaves C undefined or 0: only k = 0 is run.
  const int levels = (params.globalWarming && params.warmingLevels > 0 && pMax > 0)
                         ? params.warmingLevels
                         : 0;
  const double C = levels > 0 ? pMax / levels : 0.0;

  std::vector<std::uint8_t> seen(static_cast<std::size_t>(g.cellCount()), 0);
  std::vector<std::uint8_t> mark(seen.size(), 0);
  std::vector<CellIndex> bestPath;
  double bestScore = -1.0;
  int bestK = 0;
  int bestDistinct = 0;
  std::vector<double> levelScores;
  levelScores.reserve(static_cast<std::size_t>(levels) + 1);
  for (int k = 0; k <= levels; ++k) {
    // Eq. 8 applied k times, computed as one subtraction of k·C (the last level exactly p_max, so
    // it flattens the map completely instead of leaving rounding crumbs).
    const double offset = (k == levels) ? (levels > 0 ? pMax : 0.0) : k * C;
    Climb climb(grid, offset, params.convolutionTieBreak, seen);
    std::vector<CellIndex> path = climb.run(start, params.targets);
    int distinct = 0;
    const double score = scorePath(grid, start, path, mark, &distinct);
    levelScores.push_back(score);
    if (score > bestScore) {  // strictly: ties keep the smallest k
      bestScore = score;
      bestK = k;
      bestDistinct = distinct;
      bestPath = std::move(path);
    }
  }

  Route r = makeRoute(grid, start, std::move(bestPath));
  r.score = bestScore;
  r.distinctCells = bestDistinct;
  r.warmingLevel = bestK;
  r.levelScores = std::move(levelScores);
  return r;
}

Route lawnmower(const SearchGrid& grid, CellIndex start, int targets) {
  checkTargets(targets);
  checkStart(grid, start);
  const int rows = grid.rows();
  const int cols = grid.cols();
  std::vector<CellIndex> cells;
  cells.reserve(static_cast<std::size_t>(std::min(targets, rows * cols)));
  auto take = [&](int r, int c) {
    if (static_cast<int>(cells.size()) >= targets) return;
    if (r == start.row && c == start.col) return;
    if (grid.impassable(r, c) != 0) return;
    cells.push_back({r, c});
  };
  // A row runs east when its distance to the start row is even, west when odd.
  auto lane = [&](int r) {
    if (std::abs(r - start.row) % 2 == 0)
      for (int c = 0; c < cols; ++c) take(r, c);
    else
      for (int c = cols - 1; c >= 0; --c) take(r, c);
  };
  for (int c = start.col + 1; c < cols; ++c) take(start.row, c);  // start row, eastward part
  for (int r = start.row + 1; r < rows; ++r) lane(r);               // rows below (south)
  for (int r = start.row - 1; r >= 0; --r) lane(r);                 // rows above (north)
  for (int c = start.col - 1; c >= 0; --c) take(start.row, c);      // start row, westward part
  return scoredRoute(grid, start, std::move(cells));
}

Route scoredRoute(const SearchGrid& grid, CellIndex start, std::vector<CellIndex> cells) {
  checkStart(grid, start);
  std::vector<std::uint8_t> mark(static_cast<std::size_t>(grid.geometry().cellCount()), 0);
  int distinct = 0;
  const double score = scorePath(grid, start, cells, mark, &distinct);
  Route r = makeRoute(grid, start, std::move(cells));
  r.score = score;
  r.distinctCells = distinct;
  return r;
}

std::vector<std::pair<double, double>> accumulatedAlongRoute(const SearchGrid& grid,
                                                             const Route& route) {
  checkStart(grid, route.start);
  const GridGeometry& g = grid.geometry();
  std::vector<std::uint8_t> mark(static_cast<std::size_t>(g.cellCount()), 0);
  std::vector<std::pair<double, double>> out;
  out.reserve(route.cells.size() + 1);
  double accumulated = grid.mass(route.start.row, route.start.col);
  double distance = 0.0;
  mark[g.index(route.start)] = 1;
  out.emplace_back(distance, accumulated);
  Eigen::Vector2d prev = grid.centre(route.start);
  for (const CellIndex& c : route.cells) {
    if (!g.contains(c))
      throw Error(ErrorCode::InvalidInput, "route", "a route cell is outside the search grid");
    const Eigen::Vector2d p = grid.centre(c);
    distance += (p - prev).norm();
    prev = p;
    const int i = g.index(c);
    if (mark[i] == 0) {
      mark[i] = 1;
      accumulated += grid.mass.at(i);
    }
    out.emplace_back(distance, accumulated);
  }
  return out;
}

}  // namespace rover::team
