#include "core/team/traversal_lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "core/common/parallel.hpp"
#include "core/grid/direction.hpp"
#include "core/grid/neighbours.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

namespace {

constexpr std::int64_t kMaxWindowCells = 4'000'000;


}  // namespace

// The move table: for every cell and each of the 8 directions, the eq. 9 cost of the straight
// move between the two cell centres, or −1 when TerrainEdgeModel::edgeValid refuses it. Eq. 9
// charges roll and pitch per edge, and RRT*'s edges are up to the range (1 m) long, while a
// lattice move is one cell (0.25 m on the paper's site): charged per move as they stand, the
// attitude terms would weigh four times as much per metre on the lattice as in RRT*. They are
// scaled by move length / range so the guide prefers what RRT* prefers. Δψ is not charged (a
// lattice node does not know its incoming move); the R term keeps the guide straight.
TraversalLattice::TraversalLattice(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   double attitudeLimit, double edgeResolution,
                                   const TerrainCostWeights& weights, double range,
                                   unsigned threads)
    : dem_(dem),
      classes_(classes),
      model_(dem, classes, mapBounds(dem.geometry()), attitudeLimit, edgeResolution),
      range_(range) {
  const GridGeometry& g = classes.geometry;
  const auto n = static_cast<std::size_t>(g.cellCount());
  node_.assign(n, 0);
  cost_.assign(n * 4, kInvalid);
  // The largest cost a valid move can have (the diagonal, attitude terms just under the limit),
  // split into 65 000 steps: quantisation below 2e-5 of the largest move, far under any cost
  // difference that matters to a guide.
  const double diagonal = std::hypot(g.cellWidth, g.cellHeight);
  const double worst = weights.wR * diagonal / weights.nR +
                       (weights.wPhi * attitudeLimit / weights.nPhi +
                        weights.wTheta * attitudeLimit / weights.nTheta) * diagonal / range;
  costStep_ = worst > 0 ? worst / 65000.0 : 1.0;
  parallelFor(static_cast<std::size_t>(g.rows), threads, [&](std::size_t row) {
    const int r = static_cast<int>(row);
    for (int c = 0; c < g.cols; ++c) {
      const int i = g.index(r, c);
      const Eigen::Vector2d a = cellToLocal(g, {r, c});
      node_[i] = model_.turnValid(a) ? 1 : 0;
      // Directions E, NE, N, NW; their opposites are read from the neighbour (moveCost).
      for (int d = 0; d < 4; ++d) {
        const int rr = r + kDirRow[d], cc = c + kDirCol[d];
        if (!g.contains(rr, cc)) continue;
        const Eigen::Vector2d b = cellToLocal(g, {rr, cc});
        const std::optional<EdgeTerms> terms = model_.validEdgeTerms(a, b);
        if (!terms) continue;
        const EdgeTerms& t = *terms;
        const double attitude = weights.wPhi * t.roll / weights.nPhi +
                                weights.wTheta * t.pitch / weights.nTheta;
        const double cost = weights.wR * t.length / weights.nR + attitude * t.length / range;
        cost_[static_cast<std::size_t>(i) * 4 + d] =
            static_cast<std::uint16_t>(std::min(65000.0, std::round(cost / costStep_)));
      }
    }
  });
  // Admissible A* heuristic: the R term alone.
  heuristicPerMetre_ = weights.wR / weights.nR;
}

std::vector<int> TraversalLattice::seeds(const Eigen::Vector2d& p) const {
  const GridGeometry& g = geometry();
  std::vector<int> out;
  auto own = localToCell(g, p);
  if (!own) return out;
  out.push_back(g.index(*own));
  const double radius = 0.5;
  const int span = static_cast<int>(std::ceil(radius / std::min(g.cellWidth, g.cellHeight)));
  for (int dr = -span; dr <= span; ++dr)
    for (int dc = -span; dc <= span; ++dc) {
      const int r = own->row + dr, c = own->col + dc;
      if ((dr == 0 && dc == 0) || !g.contains(r, c)) continue;
      if (node_[g.index(r, c)] && (cellToLocal(g, {r, c}) - p).norm() <= radius)
        out.push_back(g.index(r, c));
    }
  return out;
}

// Depth first over the valid moves from the cells on `stack`: `step(i, row, col)` answers each
// move from cell i to (row, col), on the grid — Skip it, Push the cell (the caller marks it), or
// Stop the flood; true when stopped.
template <class Step>
bool TraversalLattice::flood(std::vector<int> stack, Step step) const {
  const GridGeometry& g = geometry();
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    for (const Neighbour& n : neighbours8(g, i)) {
      if (moveCost(i, n.dir) < 0) continue;
      switch (step(i, n.row, n.col)) {
        case FloodStep::Skip:
          break;
        case FloodStep::Push:
          stack.push_back(n.index);
          break;
        case FloodStep::Stop:
          return true;
      }
    }
  }
  return false;
}

Raster<std::uint8_t> TraversalLattice::reachable(const std::vector<Eigen::Vector2d>& starts) const {
  const GridGeometry& g = geometry();
  Raster<std::uint8_t> out(g, 0);
  std::vector<int> stack;
  for (const auto& s : starts)
    for (int i : seeds(s))
      if (!out.at(i)) {
        out.at(i) = 1;
        stack.push_back(i);
      }
  flood(std::move(stack), [&](int, int row, int col) {
    const int j = g.index(row, col);
    if (out.at(j) || !node_[j]) return FloodStep::Skip;
    out.at(j) = 1;
    return FloodStep::Push;
  });
  return out;
}

bool TraversalLattice::startsWithin(const Raster<std::uint8_t>& region, const Eigen::Vector2d& p) const {
  const std::vector<int> from = seeds(p);
  return !from.empty() && std::all_of(from.begin(), from.end(), [&](int i) { return region.at(i) != 0; });
}

planning::PassableGround groundIn(const Raster<std::uint8_t>& region) {
  return [&region](const Eigen::Vector2d& p) {
    const auto c = localToCell(region.geometry, p);
    return c && region(c->row, c->col) != 0;
  };
}

GroundDeparture departureOverGround(const std::vector<Eigen::Vector2d>& starts, double safety,
                                    const Raster<std::uint8_t>& region) {
  GroundDeparture out;
  if (!starts.empty()) {
    out.ground = groundIn(region);
    out.departure = planning::departureOrder(starts, safety, out.ground);
    if (out.departure.boxedIn.empty()) return out;
  }
  out.ground = {};
  out.departure = planning::departureOrder(starts, safety);
  return out;
}

// A rectangle of cells the guide's search is held to, and the cells in it that keep-out zones
// block (stamped once per window: a zone test per relaxed move cost more than the search itself
// with the 20 zones a leg's re-plans can gather).
struct TraversalLattice::Window {
  int r0, r1, c0, c1, cols;
  std::vector<std::uint8_t> blocked;  // per window cell, 1 = in a keep-out zone

  Window(const GridGeometry& g, int row0, int row1, int col0, int col1,
         const std::vector<KeepOutZone>& keepOut)
      : r0(row0), r1(row1), c0(col0), c1(col1), cols(col1 - col0 + 1),
        blocked(static_cast<std::size_t>(row1 - row0 + 1) * static_cast<std::size_t>(cols), 0) {
    for (const auto& z : keepOut) {
      // Cells whose centre lies in the disc: squared distance <= radius² (so a negative radius
      // reads as its absolute value, an infinite one blocks the window, a NaN nothing).
      if (!z.centre.allFinite() || std::isnan(z.radius)) continue;
      if (std::isinf(z.radius)) {
        std::fill(blocked.begin(), blocked.end(), 1);
        continue;
      }
      const double r2 = z.radius * z.radius;
      const double radius = std::abs(z.radius);
      // The window's columns and rows a centre in the disc can have (doubles clamped before the
      // casts, so any finite zone is safe).
      auto span = [](double a, double b, int lo, int hi) {
        return std::pair{static_cast<int>(std::clamp(std::floor(a), double(lo), double(hi + 1))),
                         static_cast<int>(std::clamp(std::floor(b), double(lo - 1), double(hi)))};
      };
      const auto [cFirst, cLast] = span((z.centre.x() - radius) / g.cellWidth,
                                        (z.centre.x() + radius) / g.cellWidth, c0, c1);
      // Rows count from the top: the disc's north edge gives the first row.
      const auto [bFirst, bLast] = span((z.centre.y() - radius) / g.cellHeight,
                                        (z.centre.y() + radius) / g.cellHeight,
                                        g.rows - 1 - r1, g.rows - 1 - r0);
      for (int r = g.rows - 1 - bLast; r <= g.rows - 1 - bFirst; ++r)
        for (int c = cFirst; c <= cLast; ++c)
          if ((cellToLocal(g, {r, c}) - z.centre).squaredNorm() <= r2) blocked[local(r, c)] = 1;
    }
  }
  bool contains(int r, int c) const { return r >= r0 && r <= r1 && c >= c0 && c <= c1; }
  bool whole(const GridGeometry& g) const {
    return r0 == 0 && c0 == 0 && r1 == g.rows - 1 && c1 == g.cols - 1;
  }
  std::size_t local(int r, int c) const {
    return static_cast<std::size_t>(r - r0) * static_cast<std::size_t>(cols) +
           static_cast<std::size_t>(c - c0);
  }
  std::size_t size() const { return blocked.size(); }
};

std::optional<std::vector<Eigen::Vector2d>> TraversalLattice::guidePath(
    const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
    const std::vector<KeepOutZone>& keepOut, bool* proven) const {
  const GridGeometry& g = geometry();
  auto goalCell = localToCell(g, goal);
  auto startCell = localToCell(g, start);
  const std::vector<int> from = seeds(start);
  bool unused = false;
  bool& certain = proven ? *proven : unused;
  certain = true;
  if (!goalCell || !startCell || from.empty()) return std::nullopt;
  const int target = g.index(*goalCell);
  // A* in a window round start and goal, widened (×4) until it holds a path or is the whole map:
  // most legs are a few metres long, and a window keeps the search's arrays small. A search that
  // failed without the window's edge stopping it has proved there is no path; so has a flood
  // back from the goal that did (a goal walled in by keep-out zones: the search from a start on
  // open ground would otherwise flood the whole map, 50 ms a time on the HiRISE site, 10 s of a
  // mission's 30 when its re-plans walled the goal in).
  const double cell = std::min(g.cellWidth, g.cellHeight);
  for (double margin = 8.0;; margin *= 4) {
    const int m = static_cast<int>(std::ceil(margin / cell));
    const int r0 = std::max(0, std::min(startCell->row, goalCell->row) - m);
    const int r1 = std::min(g.rows - 1, std::max(startCell->row, goalCell->row) + m);
    const int c0 = std::max(0, std::min(startCell->col, goalCell->col) - m);
    const int c1 = std::min(g.cols - 1, std::max(startCell->col, goalCell->col) + m);
    // Memory: 10 bytes per window cell (costs, parents, keep-out mask, the flood's marks) and
    // the open list; windows stop growing past 4 M cells (40 MB and the list), so a guide on a
    // huge map stays bounded (the leg then falls back to the boxed RRT*).
    const std::int64_t cells = static_cast<std::int64_t>(r1 - r0 + 1) * (c1 - c0 + 1);
    if (cells > kMaxWindowCells) {
      certain = false;
      return std::nullopt;
    }
    const Window w(g, r0, r1, c0, c1, keepOut);
    bool clipped = false;
    auto chain = search(from, start, target, goal, w, clipped);
    if (chain) {
      certain = false;
      return simplify(*chain, start, goal);
    }
    if (!clipped || w.whole(g)) return std::nullopt;  // certain
    bool floodClipped = false;
    if (!connected(from, target, w, floodClipped) && !floodClipped) return std::nullopt;  // certain
  }
}

// A* over the window's cells, in a deterministic order (f, cell index). `clipped`: a valid move
// left the window (a larger window may hold a path this one does not).
std::optional<std::vector<Eigen::Vector2d>> TraversalLattice::search(
    const std::vector<int>& from, const Eigen::Vector2d& start, int target,
    const Eigen::Vector2d& goal, const Window& w, bool& clipped) const {
  const GridGeometry& g = geometry();
  auto local = [&](int i) {
    const CellIndex c = g.cell(i);
    return w.local(c.row, c.col);
  };
  std::vector<float> best(w.size(), std::numeric_limits<float>::infinity());
  std::vector<int> parent(w.size(), -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  auto h = [&](int i) { return heuristicPerMetre_ * (cellToLocal(g, g.cell(i)) - goal).norm(); };
  // The start's own cell costs nothing; the other seeds cost the move to them.
  for (std::size_t k = 0; k < from.size(); ++k) {
    const int i = from[k];
    const CellIndex c = g.cell(i);
    if (!w.contains(c.row, c.col)) continue;
    const double d = k == 0 ? 0.0 : heuristicPerMetre_ * (cellToLocal(g, c) - start).norm();
    if (d < best[local(i)]) {
      best[local(i)] = static_cast<float>(d);
      open.push({d + h(i), i});
    }
  }
  bool found = false;
  while (!open.empty()) {
    const auto [f, i] = open.top();
    open.pop();
    if (f - h(i) > best[local(i)] + 1e-6) continue;  // stale entry
    if (i == target) {
      found = true;
      break;
    }
    for (const Neighbour& n : neighbours8(g, i)) {
      const float m = moveCost(i, n.dir);
      if (m < 0) continue;
      const int rr = n.row, cc = n.col;
      const int j = n.index;
      if (!node_[j] && j != target) continue;
      if (!w.contains(rr, cc)) {
        clipped = true;
        continue;
      }
      const std::size_t lj = w.local(rr, cc);
      if (w.blocked[lj]) continue;
      const float cand = best[local(i)] + m;
      if (cand < best[lj]) {
        best[lj] = cand;
        parent[lj] = i;
        open.push({cand + h(j), j});
      }
    }
  }
  if (!found) return std::nullopt;
  std::vector<Eigen::Vector2d> chain;
  for (int i = target; i >= 0; i = parent[local(i)]) chain.push_back(cellToLocal(g, g.cell(i)));
  std::reverse(chain.begin(), chain.end());
  return chain;
}

// The search's moves backwards (they are symmetric: one cost per cell pair): from the target over
// the cells the search may enter (valid nodes outside keep-out zones) until a move reaches a seed,
// which the search starts from whatever it is.
bool TraversalLattice::connected(const std::vector<int>& from, int target, const Window& w,
                                 bool& clipped) const {
  const GridGeometry& g = geometry();
  const CellIndex t = g.cell(target);
  if (!w.contains(t.row, t.col)) {
    clipped = true;
    return false;
  }
  std::vector<std::uint8_t> seen(w.size(), 0);
  for (int i : from) {
    const CellIndex c = g.cell(i);
    if (i == target) return true;
    if (w.contains(c.row, c.col)) seen[w.local(c.row, c.col)] = 2;  // 2 = a seed
  }
  // The search enters the target from any valid move, keep-out zones aside.
  if (w.blocked[w.local(t.row, t.col)]) return false;
  seen[w.local(t.row, t.col)] = 1;
  return flood({target}, [&](int, int row, int col) {
    if (!w.contains(row, col)) {
      clipped = true;
      return FloodStep::Skip;
    }
    std::uint8_t& s = seen[w.local(row, col)];
    if (s == 2) return FloodStep::Stop;
    if (s || !node_[g.index(row, col)] || w.blocked[w.local(row, col)]) return FloodStep::Skip;
    s = 1;
    return FloodStep::Push;
  });
}

std::vector<Eigen::Vector2d> TraversalLattice::simplify(const std::vector<Eigen::Vector2d>& chain,
                                                        const Eigen::Vector2d& start,
                                                        const Eigen::Vector2d& goal) const {
  // start, the centres after the start's cell, goal (the end cells' centres are replaced by the
  // real points).
  std::vector<Eigen::Vector2d> pts{start};
  auto own = localToCell(geometry(), start);
  const bool fromOwn = own && (cellToLocal(geometry(), *own) - chain.front()).squaredNorm() < 1e-12;
  pts.insert(pts.end(), chain.begin() + (fromOwn ? 1 : 0), chain.end());
  if (pts.size() > 1) pts.back() = goal;
  else pts.push_back(goal);
  // Shortcut to the farthest point within the range reachable by one valid edge ending on a
  // point where the rover may turn: fewer, straighter edges, each still valid.
  std::vector<Eigen::Vector2d> out{pts.front()};
  std::size_t i = 0;
  while (i + 1 < pts.size()) {
    std::size_t next = i + 1;
    for (std::size_t j = pts.size() - 1; j > i + 1; --j) {
      if ((pts[j] - pts[i]).norm() > range_) continue;
      if ((j + 1 == pts.size() || model_.turnValid(pts[j])) && model_.edgeValid(pts[i], pts[j])) {
        next = j;
        break;
      }
    }
    out.push_back(pts[next]);
    i = next;
  }
  return out;
}



Corridor TraversalLattice::corridor(const std::vector<Eigen::Vector2d>& path, double radius,
                                   const SearchBounds* box) const {
  const GridGeometry& g = geometry();
  Corridor out;
  out.map = g;
  Eigen::Vector2d lo = path.front(), hi = path.front();
  for (const auto& p : path) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d extent(g.widthMetres(), g.heightMetres());
  out.bounds.min = (lo.array() - radius).max(0.0).matrix();
  out.bounds.max = (hi.array() + radius).min(extent.array()).matrix();
  if (box) {
    out.bounds.min = out.bounds.min.cwiseMin(box->min);
    out.bounds.max = out.bounds.max.cwiseMax(box->max);
  }
  const int c0 = std::clamp(static_cast<int>(std::floor(out.bounds.min.x() / g.cellWidth)), 0, g.cols - 1);
  const int c1 = std::clamp(static_cast<int>(std::floor(out.bounds.max.x() / g.cellWidth)), 0, g.cols - 1);
  const int r0 = std::clamp(g.rows - 1 - static_cast<int>(std::floor(out.bounds.max.y() / g.cellHeight)), 0, g.rows - 1);
  const int r1 = std::clamp(g.rows - 1 - static_cast<int>(std::floor(out.bounds.min.y() / g.cellHeight)), 0, g.rows - 1);
  out.row0 = r0;
  out.col0 = c0;
  out.mask = Raster<std::uint8_t>(GridGeometry{r1 - r0 + 1, c1 - c0 + 1, g.cellWidth, g.cellHeight}, 0);
  const double step = 0.5 * std::min(g.cellWidth, g.cellHeight);
  const int span = static_cast<int>(std::ceil(radius / std::min(g.cellWidth, g.cellHeight))) + 1;
  auto stamp = [&](const Eigen::Vector2d& p) {
    auto c = localToCell(g, p);
    if (!c) return;
    for (int dr = -span; dr <= span; ++dr)
      for (int dc = -span; dc <= span; ++dc) {
        const int r = c->row + dr, k = c->col + dc;
        if (r < r0 || r > r1 || k < c0 || k > c1) continue;
        if ((cellToLocal(g, {r, k}) - p).squaredNorm() <= radius * radius) out.mask(r - r0, k - c0) = 1;
      }
  };
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const int n = std::max(1, static_cast<int>(std::ceil((path[i + 1] - path[i]).norm() / step)));
    for (int s = 0; s < n; ++s) stamp(path[i] + (path[i + 1] - path[i]) * (static_cast<double>(s) / n));
  }
  stamp(path.back());
  if (box) {  // every cell the box touches
    auto a = localToCell(g, box->min), b = localToCell(g, box->max);
    if (a && b)
      for (int r = b->row; r <= a->row; ++r)
        for (int k = a->col; k <= b->col; ++k) out.mask(r - r0, k - c0) = 1;
  }
  return out;
}

}  // namespace rover::team
