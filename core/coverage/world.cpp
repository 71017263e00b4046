#include "core/coverage/world.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/grid/neighbours.hpp"

namespace rover::coverage {

int addKeepOut(World& world, const KeepOut& keepOut) {
  if (keepOut.empty()) return 0;
  const std::vector<std::uint8_t> cells = keepOut.cells(world.geometry());
  int added = 0;
  for (int i = 0; i < world.geometry().cellCount(); ++i)
    if (cells[static_cast<std::size_t>(i)] && !world.obstacles.at(i)) {
      world.obstacles.at(i) = 1;
      ++added;
    }
  return added;
}

int World::obstacleCount() const {
  const auto& v = obstacles.values;
  return static_cast<int>(std::count_if(v.data(), v.data() + v.size(), [](auto o) { return o; }));
}

void validateWorld(const World& world) {
  const GridGeometry& g = world.geometry();
  if (g.rows < 2 || g.cols < 2)
    throw Error(ErrorCode::InvalidInput, "rows", "the coverage grid needs at least 2×2 cells");
  if (!(g.cellWidth > 0) || !std::isfinite(g.cellWidth) || std::fabs(g.cellWidth - g.cellHeight) > 1e-9 * g.cellWidth)
    throw Error(ErrorCode::InvalidInput, "cell", "coverage cells must be square and positive");
  if (world.hasHeights()) {
    const GridGeometry& h = world.heights.geometry;
    if (h.rows != g.rows || h.cols != g.cols)
      throw Error(ErrorCode::InvalidInput, "heights", "height grid size differs from the world");
    if (!world.heights.values.allFinite())
      throw Error(ErrorCode::InvalidInput, "heights", "height grid holds NaN or infinite values");
  }
  if (world.freeCount() == 0)
    throw Error(ErrorCode::InvalidInput, "obstacles", "the world has no free cell");
}

namespace {

// Would turning free cell `idx` into an obstacle keep its free 8-neighbours connected among
// themselves? Ring neighbours are adjacent when consecutive, and two orthogonal neighbours two
// steps apart (E and N, ...) touch diagonally. If the free ring stays connected, any path through
// the cell can go round it, so global connectivity is preserved (conservative test).
bool ringStaysConnected(const Raster<std::uint8_t>& obs, int row, int col) {
  const GridGeometry& g = obs.geometry;
  std::array<bool, 8> freeRing{};  // off the grid: not free
  int freeCount = 0;
  for (const Neighbour& n : neighbours8(g, CellIndex{row, col})) {
    freeRing[n.dir] = obs.at(n.index) == 0;
    freeCount += freeRing[n.dir];
  }
  if (freeCount <= 1) return freeCount == 1;  // 0 would delete an isolated cell: never happens
  std::array<int, 8> parent{};
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto unite = [&](int a, int b) {
    if (freeRing[a] && freeRing[b]) parent[find(a)] = find(b);
  };
  for (int d = 0; d < 8; ++d) {
    unite(d, (d + 1) % 8);
    if (d % 2 == 0) unite(d, (d + 2) % 8);
  }
  int root = -1;
  for (int d = 0; d < 8; ++d) {
    if (!freeRing[d]) continue;
    if (root < 0)
      root = find(d);
    else if (find(d) != root)
      return false;
  }
  return true;
}

}  // namespace

World generateWorld(const WorldParams& p) {
  if (p.rows < 2 || p.rows > 4096) throwInvalidParameter("rows", "must be in [2, 4096]");
  if (p.cols < 2 || p.cols > 4096) throwInvalidParameter("cols", "must be in [2, 4096]");
  if (!(p.cellSize > 0) || !std::isfinite(p.cellSize))
    throwInvalidParameter("cell", "must be a positive number of metres");
  if (!(p.obstacleFraction >= 0 && p.obstacleFraction <= 0.9))
    throwInvalidParameter("obstacles", "must be in [0, 0.9]");

  GridGeometry g{p.rows, p.cols, p.cellSize, p.cellSize};
  World w;
  w.obstacles = Raster<std::uint8_t>(g, 0);
  const int n = g.cellCount();
  const int target = static_cast<int>(std::lround(p.obstacleFraction * n));

  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  Rng rng(deriveSeed(p.seed, 1));
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[rng.below(i + 1)]);  // Fisher–Yates

  int placed = 0;
  for (int i = 0; i < n && placed < target && placed < n - 1; ++i) {
    CellIndex c = g.cell(order[i]);
    if (!p.allowSealed && !ringStaysConnected(w.obstacles, c.row, c.col)) continue;
    w.obstacles.at(order[i]) = 1;
    ++placed;
  }
  return w;
}

std::vector<std::uint8_t> reachableCells(const World& world, const std::vector<int>& starts,
                                         const std::vector<std::uint8_t>& allowed) {
  const GridGeometry& g = world.geometry();
  std::vector<std::uint8_t> seen(g.cellCount(), 0);
  std::vector<int> stack;
  auto ok = [&](int i) { return !world.isObstacle(i) && (allowed.empty() || allowed[i]); };
  for (int s : starts) {
    if (s >= 0 && s < g.cellCount() && ok(s) && !seen[s]) {
      seen[s] = 1;
      stack.push_back(s);
    }
  }
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    for (const Neighbour& n : neighbours8(g, i)) {
      const int j = n.index;
      if (!seen[j] && ok(j)) {
        seen[j] = 1;
        stack.push_back(j);
      }
    }
  }
  return seen;
}

std::vector<int> freeComponents(const World& world, std::vector<int>& sizes) {
  const GridGeometry& g = world.geometry();
  const int n = g.cellCount();
  std::vector<int> label(static_cast<std::size_t>(n), -1);
  sizes.clear();
  // The stack holds each cell once at most: sized once, used as a plain array (raw pointers, so
  // the label writes do not make the compiler reload the world's arrays per neighbour).
  std::vector<int> stackStore(static_cast<std::size_t>(n));
  int* const stack = stackStore.data();
  int* const lab = label.data();
  const std::uint8_t* const obstacle = world.obstacles.values.data();
  for (int s = 0; s < n; ++s) {
    if (obstacle[s] || lab[s] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    int size = 0, top = 0;
    lab[s] = id;
    stack[top++] = s;
    while (top > 0) {
      const int i = stack[--top];
      ++size;
      auto reach = [&](int j) {
        if (lab[j] < 0 && !obstacle[j]) {
          lab[j] = id;
          stack[top++] = j;
        }
      };
      // Every coverage run floods its world once (random starts): a cell off the border takes
      // its neighbours by fixed offsets, without the range's division and bounds tests.
      const int row = i / g.cols, col = i - row * g.cols;
      if (row > 0 && row < g.rows - 1 && col > 0 && col < g.cols - 1) {
        for (int dir = 0; dir < kDirections; ++dir) reach(i + kDirRow[dir] * g.cols + kDirCol[dir]);
      } else {
        for (const Neighbour& nb : neighbours8(g, CellIndex{row, col})) reach(nb.index);
      }
    }
    sizes.push_back(size);
  }
  return label;
}

}  // namespace rover::coverage
