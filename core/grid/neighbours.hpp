#pragma once
// The in-grid 8-neighbours of a cell as a small range, after grid_map's iterators: a loop reads
// `for (const Neighbour& n : neighbours8(g, cell))` instead of repeating the direction tables and
// the bounds test. Directions come in counter-clockwise order (core/grid/direction.hpp) from
// `firstDir`, so a rover's "straight, left 45°, ..." order is `neighbours8(g, cell, heading)`;
// neighbours off the grid are skipped.
#include "core/grid/direction.hpp"
#include "core/grid/geometry.hpp"

namespace rover {

struct Neighbour {
  int dir = 0;  // 0..7, the move from the centre cell
  int row = 0;
  int col = 0;
  int index = 0;  // row * cols + col
};

class Neighbours8 {
 public:
  Neighbours8(const GridGeometry& g, CellIndex centre, int firstDir)
      : g_(&g),
        centre_(centre),
        first_(firstDir),
        interior_(centre.row > 0 && centre.row < g.rows - 1 && centre.col > 0 && centre.col < g.cols - 1) {}

  class Iterator {
   public:
    Iterator(const Neighbours8* range, int k) : range_(range), k_(k) { skipOffGrid(); }
    Neighbour operator*() const { return current_; }
    Iterator& operator++() {
      ++k_;
      skipOffGrid();
      return *this;
    }
    bool operator==(const Iterator& o) const { return k_ == o.k_; }

   private:
    void skipOffGrid() {
      for (; k_ < kDirections; ++k_) {
        const int dir = (range_->first_ + k_) & 7;
        const int row = range_->centre_.row + kDirRow[dir], col = range_->centre_.col + kDirCol[dir];
        if (range_->interior_ || range_->g_->contains(row, col)) {
          current_ = {dir, row, col, range_->g_->index(row, col)};
          return;
        }
      }
    }
    const Neighbours8* range_;
    int k_;
    Neighbour current_;
  };

  Iterator begin() const { return {this, 0}; }
  Iterator end() const { return {this, kDirections}; }

 private:
  const GridGeometry* g_;
  CellIndex centre_;
  int first_;
  bool interior_;  // no neighbour off the grid: no bounds test per neighbour
};

// `firstDir` may be any direction, negative or past 7 (it is taken modulo 8).
inline Neighbours8 neighbours8(const GridGeometry& g, CellIndex centre, int firstDir = 0) {
  return {g, centre, rotateDir(firstDir, 0)};
}
inline Neighbours8 neighbours8(const GridGeometry& g, int index, int firstDir = 0) {
  return neighbours8(g, g.cell(index), firstDir);
}

// Direction of the move from `from` to its 8-neighbour `to`, from the flat offset alone: the
// coverage engine asks it every move, and GridGeometry::cell's divisions were a tenth of a
// study's time. On grids under 3 columns two offsets coincide (E and NE when cols = 2), so
// those take the division.
inline int neighbourDir(const GridGeometry& g, int from, int to) {
  if (g.cols < 3) {
    const CellIndex a = g.cell(from), b = g.cell(to);
    return dirOf(b.row - a.row, b.col - a.col);
  }
  const int d = to - from;
  const int dRow = d < -1 ? -1 : (d > 1 ? 1 : 0);
  return dirOf(dRow, d - dRow * g.cols);
}

}  // namespace rover
