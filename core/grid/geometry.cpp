#include "core/grid/geometry.hpp"

#include <cmath>

namespace rover {

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
