#pragma once
// Grid geometry and the one pair of (row, col) <-> local (x, y) conversions (SPEC §0).
// Grid: row 0 at the top (north), col 0 at the west. Local frame: x east, y north, in metres from
// the raster's lower-left (south-west) corner. Positions refer to cell centres.
#include <Eigen/Core>
#include <optional>

namespace rover {

struct CellIndex {
  int row = 0;
  int col = 0;
  friend bool operator==(const CellIndex&, const CellIndex&) = default;
};

struct GridGeometry {
  int rows = 0;
  int cols = 0;
  double cellWidth = 1.0;   // metres along x (east)
  double cellHeight = 1.0;  // metres along y (north)

  int cellCount() const { return rows * cols; }
  bool contains(int row, int col) const { return row >= 0 && row < rows && col >= 0 && col < cols; }
  bool contains(CellIndex c) const { return contains(c.row, c.col); }
  int index(int row, int col) const { return row * cols + col; }
  int index(CellIndex c) const { return index(c.row, c.col); }
  CellIndex cell(int index) const { return {index / cols, index % cols}; }
  double widthMetres() const { return cols * cellWidth; }
  double heightMetres() const { return rows * cellHeight; }
};

// Centre of a cell in the local frame.
Eigen::Vector2d cellToLocal(const GridGeometry& g, CellIndex c);
// The cell containing a local point; nullopt outside the grid. Points on the east/north edge of the
// grid belong to the last column/first row.
std::optional<CellIndex> localToCell(const GridGeometry& g, const Eigen::Vector2d& xy);

}  // namespace rover
