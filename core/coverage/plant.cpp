#include "core/coverage/plant.hpp"

#include <algorithm>
#include <cstdlib>
#include <numbers>

#include "core/grid/direction.hpp"
#include "core/grid/neighbours.hpp"

namespace rover::coverage {

void senseWindow(const World& world, int radius, KnowledgeMap& map, int believedCell, int trueCell,
                 Recorder& recorder) {
  // Beyond the field's edge is an obstacle (only a true window off the grid meets it).
  const GridGeometry& g = world.geometry();
  const CellIndex c = g.cell(believedCell), t = g.cell(trueCell);
  const int r0 = std::max(0, c.row - radius), r1 = std::min(g.rows - 1, c.row + radius);
  const int c0 = std::max(0, c.col - radius), c1 = std::min(g.cols - 1, c.col + radius);
  for (int row = r0; row <= r1; ++row) {
    for (int col = c0; col <= c1; ++col) {
      const int i = g.index(row, col);
      if (!map.inRegion(i)) continue;
      bool obstacle;
      if (believedCell == trueCell) {
        obstacle = world.isObstacle(i);
      } else {
        const int tr = t.row + row - c.row, tc = t.col + col - c.col;
        obstacle = !g.contains(tr, tc) || world.isObstacle(g.index(tr, tc));
      }
      if (map.sense(i, obstacle)) recorder.cellChanged(i, map.state(i), 0);
    }
  }
}

namespace {

// The believed pose is the true pose.
class PerfectPlant final : public Plant {
 public:
  PerfectPlant(const World& world, const CoverageParams& params, TeamOccupancy& team, Recorder& recorder,
               std::size_t rovers)
      : Plant(true),
        world_(world),
        g_(world.geometry()),
        radius_(params.senseRadius),
        length_{g_.cellWidth * 1.0, g_.cellWidth * std::numbers::sqrt2},
        team_(team),
        recorder_(recorder),
        lastSensed_(rovers, kNotYet) {}

  void sense(const CoverageRover& r) override;
  Drive drive(CoverageRover& r, int next, int dir, std::int64_t, Motion& motion) override {
    motion.horizontal = length_[isDiagonal(dir)];
    motion.dh = world_.height(next) - world_.height(r.cell);
    return Drive::Moved;
  }
  void arrived(CoverageRover&) override {}
  bool stopsWalledIn() const override { return false; }
  int trueVisited() const override { return team_.visitedTotal(); }
  int visitedTrulyReached() const override { return team_.visitedTotal(); }
  RoverPose pose(const CoverageRover& r) const override {
    const Eigen::Vector2d xy = cellToLocal(g_, g_.cell(r.cell));
    return {r.id, xy.x(), xy.y(), dirToRadians(r.heading)};
  }
  void summarise(CoverageResult&) const override {}

 private:
  const World& world_;
  const GridGeometry& g_;
  const int radius_;
  // Metres of a straight and of a diagonal one-cell move.
  const double length_[2];
  TeamOccupancy& team_;
  Recorder& recorder_;
  // The row and column of `cell`, a neighbour of `from` (or `from` itself) after a move, found
  // from the flat offset; GridGeometry::cell's division only for anything else.
  CellIndex cellAfter(CellIndex from, int cell) const {
    if (from.row >= 0 && g_.cols >= 3) {
      const int d = cell - g_.index(from);
      const int dRow = d < -1 ? -1 : (d > 1 ? 1 : 0);
      const CellIndex c{from.row + dRow, from.col + d - dRow * g_.cols};
      if (c.col >= 0 && c.col < g_.cols && c.col - from.col >= -1 && c.col - from.col <= 1 && g_.contains(c))
        return c;
    }
    return g_.cell(cell);
  }

  // Per rover, the cell it last sensed from (row and column: no division to find them again).
  static constexpr CellIndex kNotYet{-1, -1};
  std::vector<CellIndex> lastSensed_;
};

void PerfectPlant::sense(const CoverageRover& r) {
  // Every cell within R of the cell the rover last sensed from is known already (the map never
  // forgets under a perfect pose), so after a one-cell move only the row and column the move
  // brought into range are read, in the same row-major order as the whole window.
  KnowledgeMap& m = team_.map(r.mapId);
  if (m.unknownCells() == 0) return;  // nothing left to learn, and nothing is ever forgotten
  CellIndex& last = lastSensed_[r.id];
  const CellIndex p = last;
  const CellIndex c = cellAfter(p, r.cell);
  last = c;
  if (p.row < 0 || std::abs(p.row - c.row) > 1 || std::abs(p.col - c.col) > 1) {
    senseWindow(world_, radius_, team_.map(r.mapId), r.cell, r.cell, recorder_);
    return;
  }
  // Moved by (dr, dc), each -1..1: the row c.row + dr·R and the column c.col + dc·R came into
  // range (the parts inside the grid), read row by row.
  const int R = radius_;
  const int dr = c.row - p.row, dc = c.col - p.col;
  const int newRow = dr != 0 ? c.row + dr * R : -1;
  const int newCol = c.col + dc * R;
  const bool colInGrid = dc != 0 && newCol >= 0 && newCol < g_.cols;
  const int r0 = std::max(0, c.row - R), r1 = std::min(g_.rows - 1, c.row + R);
  const int c0 = std::max(0, c.col - R), c1 = std::min(g_.cols - 1, c.col + R);
  const std::uint8_t* const truth = world_.obstacles.values.data();
  auto changed = [&](int i, CellState s) { recorder_.cellChanged(i, s, 0); };
  const int width = c1 - c0 + 1;
  if (newRow < r0 || newRow > r1) {  // only the new column (if any) is in the grid
    if (colInGrid) m.senseLine(g_.index(r0, newCol), g_.cols, r1 - r0 + 1, truth, changed);
    return;
  }
  // Row-major as the whole window: the column above the new row, the row, the column below.
  if (colInGrid) m.senseLine(g_.index(r0, newCol), g_.cols, newRow - r0, truth, changed);
  m.senseLine(g_.index(newRow, c0), 1, width, truth, changed);
  if (colInGrid) m.senseLine(g_.index(newRow + 1, newCol), g_.cols, r1 - newRow, truth, changed);
}

}  // namespace

std::unique_ptr<Plant> makePlant(const World& world, const CoverageParams& params, TeamOccupancy& team,
                                 Recorder& recorder, const std::vector<CoverageRover>& rovers) {
  if (params.localisation.active()) return makeDeadReckoningPlant(world, params, team, recorder, rovers);
  return std::make_unique<PerfectPlant>(world, params, team, recorder, rovers.size());
}

}  // namespace rover::coverage
