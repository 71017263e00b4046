#pragma once
// Grid geometry and the one pair of (row, col) <-> local (x, y) conversions (SPEC §0).
// Grid: row 0 at the top (north), col 0 at the west. Local frame: x east, y north, in metres from
// the raster's lower-left (south-west) corner. Positions refer to cell centres.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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

// Throws rover::Error (InvalidInput, `field`) unless the grid has cells and its cell sizes are
// finite positive metres. The boundary every planner is reached through (planning::
// checkMissionStarts) calls it, so a map whose georeferencing gave a NaN or zero cell size (issue
// 22: a segfault in the start check) is refused as bad input, never planned on.
void checkGridGeometry(const GridGeometry& g, const std::string& field = "map");

// Centre of a cell in the local frame.
Eigen::Vector2d cellToLocal(const GridGeometry& g, CellIndex c);
// The cell containing a local point; nullopt outside the grid. Points on the east/north edge of the
// grid belong to the last column/first row.
std::optional<CellIndex> localToCell(const GridGeometry& g, const Eigen::Vector2d& xy);

// A polygon in the local frame: its rings (the first the outline, any others holes), each an
// open list of vertices (the closing vertex not repeated). Inside is the even-odd rule over all
// rings, so a hole is outside and self-intersections need no special case.
using Ring = std::vector<Eigen::Vector2d>;
using Polygon = std::vector<Ring>;

// Strictly inside `polygon` (even-odd crossing test, Shimrat 1962 / Haines 1994); a point on an
// edge may answer either way.
bool insidePolygon(const Polygon& polygon, const Eigen::Vector2d& p);

// The cells of `g` that overlap any of `polygons` with positive area (the one rasterisation of
// keep-out zones): a cell is marked when its centre is inside, or when an edge passes through the
// cell's interior, so a polygon that only touches a cell's border does not mark it. `grow` > 0
// grows every cell by that many metres on each side first (a square margin: the cells within
// `grow` of the polygon, measured along x and y). Row-major flags, 1 = marked. Cost: per polygon,
// O(rows it spans × edges + cells marked).
std::vector<std::uint8_t> polygonCells(const GridGeometry& g, const std::vector<Polygon>& polygons,
                                       double grow = 0);

}  // namespace rover
