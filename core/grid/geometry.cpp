#include "core/grid/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/common/error.hpp"

namespace rover {

void checkGridGeometry(const GridGeometry& g, const std::string& field) {
  if (g.rows < 1 || g.cols < 1)
    throw Error(ErrorCode::InvalidInput, field, field + ": the grid has no cells");
  if (!(g.cellWidth > 0 && g.cellHeight > 0 && std::isfinite(g.cellWidth) && std::isfinite(g.cellHeight))) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%g x %g m", g.cellWidth, g.cellHeight);
    throw Error(ErrorCode::InvalidInput, field,
                field + ": the cell size must be finite positive metres, not " + std::string(buf));
  }
}

Eigen::Vector2d cellToLocal(const GridGeometry& g, CellIndex c) {
  return {(c.col + 0.5) * g.cellWidth, (g.rows - c.row - 0.5) * g.cellHeight};
}

std::optional<CellIndex> localToCell(const GridGeometry& g, const Eigen::Vector2d& xy) {
  if (!std::isfinite(xy.x()) || !std::isfinite(xy.y())) return std::nullopt;
  if (xy.x() < 0 || xy.y() < 0 || xy.x() > g.widthMetres() || xy.y() > g.heightMetres())
    return std::nullopt;
  int col = static_cast<int>(std::floor(xy.x() / g.cellWidth));
  int rowFromBottom = static_cast<int>(std::floor(xy.y() / g.cellHeight));
  if (col == g.cols) col = g.cols - 1;
  if (rowFromBottom == g.rows) rowFromBottom = g.rows - 1;
  return CellIndex{g.rows - 1 - rowFromBottom, col};
}

}  // namespace rover

namespace rover {

bool insidePolygon(const Polygon& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (const Ring& ring : polygon) {
    const std::size_t n = ring.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      const Eigen::Vector2d &a = ring[i], &b = ring[j];
      // Half-open in y: a vertex on the ray's line counts for one of its two edges only.
      if ((a.y() > p.y()) != (b.y() > p.y()) &&
          p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
        inside = !inside;
    }
  }
  return inside;
}

namespace {

// Marks cols c0..c1 of row `row` (clipped to the grid).
void markSpan(const GridGeometry& g, std::vector<std::uint8_t>& out, int row, int c0, int c1) {
  if (row < 0 || row >= g.rows) return;
  c0 = std::max(c0, 0);
  c1 = std::min(c1, g.cols - 1);
  for (int c = c0; c <= c1; ++c) out[static_cast<std::size_t>(g.index(row, c))] = 1;
}

}  // namespace

// Two passes per polygon. (1) Centres: per row, the x where the row's centre line crosses the
// edges (the same half-open rule as insidePolygon), sorted; the cells whose centre lies between
// the 1st and 2nd, 3rd and 4th, ... crossing are inside. (2) Edges: per row band an edge crosses,
// the x-range of the edge within the band (the band and the cells shrunk by 1e-9 of a cell, so
// an edge along a cell border marks neither side, or grown by `grow`), and the cells over it.
// A cell an edge does not pass through is wholly inside or wholly outside, which its centre says.
std::vector<std::uint8_t> polygonCells(const GridGeometry& g, const std::vector<Polygon>& polygons,
                                       double grow) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(g.cellCount()), 0);
  if (g.cellCount() == 0) return out;
  const double H = g.heightMetres(), w = g.cellWidth, h = g.cellHeight;
  const double shrinkX = 1e-9 * w - grow, shrinkY = 1e-9 * h - grow;
  // Row r spans y in [H − (r+1)·h, H − r·h].
  auto rowOfY = [&](double y) { return static_cast<int>(std::floor((H - y) / h)); };
  std::vector<double> xs;
  for (const Polygon& poly : polygons) {
    double ylo = INFINITY, yhi = -INFINITY;
    for (const Ring& ring : poly)
      for (const auto& v : ring) {
        ylo = std::min(ylo, v.y());
        yhi = std::max(yhi, v.y());
      }
    if (!(ylo <= yhi)) continue;
    // (1) centres
    const int r0 = std::max(0, rowOfY(yhi)), r1 = std::min(g.rows - 1, rowOfY(ylo));
    for (int r = r0; r <= r1; ++r) {
      const double y = H - (r + 0.5) * h;
      xs.clear();
      for (const Ring& ring : poly) {
        const std::size_t n = ring.size();
        for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
          const Eigen::Vector2d &a = ring[i], &b = ring[j];
          if ((a.y() > y) != (b.y() > y))
            xs.push_back((b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()) + a.x());
        }
      }
      std::sort(xs.begin(), xs.end());
      for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
        // Cells with xs[k] < centre < xs[k+1]: centre = (c + 0.5)·w.
        const int c0 = static_cast<int>(std::floor(xs[k] / w - 0.5)) + 1;
        const int c1 = static_cast<int>(std::ceil(xs[k + 1] / w - 0.5)) - 1;
        markSpan(g, out, r, c0, c1);
      }
    }
    // (2) edges
    for (const Ring& ring : poly) {
      const std::size_t n = ring.size();
      for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
        const Eigen::Vector2d &a = ring[j], &b = ring[i];
        const double eyLo = std::min(a.y(), b.y()), eyHi = std::max(a.y(), b.y());
        const int er0 = std::max(0, rowOfY(eyHi + grow) - 1);
        const int er1 = std::min(g.rows - 1, rowOfY(eyLo - grow) + 1);
        for (int r = er0; r <= er1; ++r) {
          // The band's open interior, shrunk (or grown).
          const double bLo = H - (r + 1) * h + shrinkY, bHi = H - r * h - shrinkY;
          const double lo = std::max(bLo, eyLo), hi = std::min(bHi, eyHi);
          if (lo > hi) continue;
          double xa, xb;
          if (a.y() == b.y()) {
            xa = std::min(a.x(), b.x());
            xb = std::max(a.x(), b.x());
          } else {
            const double ta = (lo - a.y()) / (b.y() - a.y()), tb = (hi - a.y()) / (b.y() - a.y());
            const double x1 = a.x() + ta * (b.x() - a.x()), x2 = a.x() + tb * (b.x() - a.x());
            xa = std::min(x1, x2);
            xb = std::max(x1, x2);
          }
          // Cells whose shrunk (grown) x-interval [c·w + sx, (c+1)·w − sx] meets [xa, xb].
          const int c0 = static_cast<int>(std::floor((xa + shrinkX) / w));
          const int c1 = static_cast<int>(std::floor((xb - shrinkX) / w));
          int from = c0, to = c1;
          // floor can land one cell off at the exact borders: check the ends exactly.
          while (from <= to && (from + 1) * w - shrinkX < xa) ++from;
          while (to >= from && to * w + shrinkX > xb) --to;
          markSpan(g, out, r, from, to);
        }
      }
    }
  }
  return out;
}

}  // namespace rover
