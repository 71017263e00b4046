#include "core/coverage/plant.hpp"

#include <algorithm>
#include <array>
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
               std::size_t rovers);

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
  // After a one-cell move from `from` to `to`: the row and column the move brought into range,
  // clipped to the grid.
  void senseEntering(KnowledgeMap& m, CellIndex from, CellIndex to);

  const World& world_;
  const GridGeometry& g_;
  const int radius_;
  // Metres of a straight and of a diagonal one-cell move.
  const double length_[2];
  TeamOccupancy& team_;
  Recorder& recorder_;
  // Per rover, the cell it last sensed from (-1 before its first sensing).
  std::vector<int> lastSensed_;
  // Cells whose window of radius R lies inside the grid, and per direction of a move the offsets
  // from the new cell of the cells entering its window, in the window's row-major order: a move
  // between two such cells reads them without clipping anything.
  std::vector<std::uint8_t> inner_;
  std::array<std::vector<int>, 8> entering_;
};

PerfectPlant::PerfectPlant(const World& world, const CoverageParams& params, TeamOccupancy& team,
                           Recorder& recorder, std::size_t rovers)
    : Plant(true),
      world_(world),
      g_(world.geometry()),
      radius_(params.senseRadius),
      length_{g_.cellWidth * 1.0, g_.cellWidth * std::numbers::sqrt2},
      team_(team),
      recorder_(recorder),
      lastSensed_(rovers, -1),
      inner_(static_cast<std::size_t>(g_.cellCount()), 0) {
  const int R = radius_;
  for (int row = R; row < g_.rows - R; ++row)
    for (int col = R; col < g_.cols - R; ++col) inner_[static_cast<std::size_t>(g_.index(row, col))] = 1;
  for (int dir = 0; dir < kDirections; ++dir)
    for (int dRow = -R; dRow <= R; ++dRow)
      for (int dCol = -R; dCol <= R; ++dCol) {
        // In the new window; in the old one (centred one step back) unless this far ahead.
        const int oldRow = dRow + kDirRow[dir], oldCol = dCol + kDirCol[dir];
        if (std::abs(oldRow) > R || std::abs(oldCol) > R) entering_[dir].push_back(dRow * g_.cols + dCol);
      }
}

void PerfectPlant::sense(const CoverageRover& r) {
  // Every cell within R of the cell the rover last sensed from is known already (the map never
  // forgets under a perfect pose), so after a one-cell move only the row and column the move
  // brought into range are read, in the same row-major order as the whole window.
  KnowledgeMap& m = team_.map(r.mapId);
  if (m.unknownCells() == 0) return;  // nothing left to learn, and nothing is ever forgotten
  const int from = lastSensed_[static_cast<std::size_t>(r.id)];
  lastSensed_[static_cast<std::size_t>(r.id)] = r.cell;
  auto changed = [&](int i, CellState s) { recorder_.cellChanged(i, s, 0); };
  if (from >= 0 && inner_[static_cast<std::size_t>(r.cell)]) {
    // The move's direction from the flat offset: exact, as the new cell is off the border.
    const int d = r.cell - from;
    const int dRow = d < -1 ? -1 : (d > 1 ? 1 : 0), dCol = d - dRow * g_.cols;
    if (d != 0 && dCol >= -1 && dCol <= 1) {
      m.senseAround(r.cell, entering_[static_cast<std::size_t>(dirOf(dRow, dCol))],
                    world_.obstacles.values.data(), changed);
      return;
    }
  }
  const CellIndex c = g_.cell(r.cell);
  const CellIndex p = from >= 0 ? g_.cell(from) : CellIndex{-1, -1};
  if (p.row < 0 || std::abs(p.row - c.row) > 1 || std::abs(p.col - c.col) > 1) {
    senseWindow(world_, radius_, m, r.cell, r.cell, recorder_);
    return;
  }
  senseEntering(m, p, c);
}

void PerfectPlant::senseEntering(KnowledgeMap& m, CellIndex p, CellIndex c) {
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
