#include "core/coverage/knowledge_map.hpp"

#include <algorithm>
#include <cmath>

namespace rover::coverage {

KnowledgeMap::KnowledgeMap(const GridGeometry& g, std::vector<std::uint8_t> region)
    : geometry_(g),
      region_(std::move(region)),
      state_(g.cellCount(), CellState::Unknown),
      visits_(g.cellCount(), 0) {
  regionCells_ = region_.empty() ? g.cellCount()
                                 : static_cast<int>(std::count(region_.begin(), region_.end(), 1));
  unknown_ = regionCells_;
}

bool KnowledgeMap::markObstacle(int i) {
  if (state_[i] == CellState::Obstacle) return false;
  if (state_[i] == CellState::Visited) --visited_;
  if (state_[i] == CellState::Unknown && inRegion(i)) --unknown_;
  state_[i] = CellState::Obstacle;
  visits_[i] = 0;
  ++knownObstacles_;
  return true;
}

int KnowledgeMap::neededFor(double goal) const {
  // The small epsilon keeps e.g. 0.95 · 3420 = 3249 from needing 3250 through rounding.
  double needed = goal * static_cast<double>(regionCells_ - knownObstacles_);
  return static_cast<int>(std::ceil(needed - 1e-9));
}

}  // namespace rover::coverage
