#include "core/coverage/team_occupancy.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "core/common/error.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::coverage {

TeamOccupancy::TeamOccupancy(const World& world, const std::vector<StartCell>& starts, TeamMode mode)
    : world_(world), occupant_(static_cast<std::size_t>(world.geometry().cellCount()), kNoRover) {
  const GridGeometry& g = world.geometry();
  const int n = g.cellCount();
  planning::checkRoverCount(starts.size());
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const std::string field = "rovers[" + std::to_string(k) + "]";
    const StartCell& s = starts[k];
    if (s.cell < 0 || s.cell >= n)
      throw Error(ErrorCode::InvalidInput, field, field + ": start is outside the grid");
    if (world.isObstacle(s.cell))
      throw Error(ErrorCode::InvalidInput, field, field + ": start is on an obstacle");
    if (s.heading < 0 || s.heading > 7)
      throw Error(ErrorCode::InvalidInput, field, field + ": heading must be a direction 0..7");
    if (occupant(s.cell) != kNoRover)
      throw Error(ErrorCode::InvalidInput, field, field + ": two rovers start on one cell");
    occupant_[static_cast<std::size_t>(s.cell)] = static_cast<int>(k);
    starts_.push_back(s.cell);
  }

  const int count = static_cast<int>(starts.size());
  if (mode == TeamMode::Voronoi && count > 1) {
    // Paper 002 §2.3 "environment sharing": each cell goes to the nearest initial rover position.
    region_.assign(static_cast<std::size_t>(n), 0);
    for (int i = 0; i < n; ++i) {
      const CellIndex c = g.cell(i);
      long best = std::numeric_limits<long>::max();
      for (int k = 0; k < count; ++k) {
        const CellIndex s = g.cell(starts[static_cast<std::size_t>(k)].cell);
        const long dr = c.row - s.row, dc = c.col - s.col;
        const long d2 = dr * dr + dc * dc;
        if (d2 < best) best = d2, region_[static_cast<std::size_t>(i)] = k;
      }
    }
    for (int k = 0; k < count; ++k) {
      std::vector<std::uint8_t> mask(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) mask[static_cast<std::size_t>(i)] = region_[static_cast<std::size_t>(i)] == k;
      maps_.emplace_back(g, std::move(mask));
    }
  } else {
    maps_.emplace_back(g);
  }
}

int TeamOccupancy::reachableCells(int visitedTrulyReached) const {
  // Every truly entered cell is reachable and reachable cells are free: all free cells entered
  // means all free cells reachable.
  const int free = world_.freeCount();
  if (visitedTrulyReached == free) return free;
  std::vector<std::uint8_t> reachable;
  if (regionsApart()) {
    const std::size_t n = region_.size();
    reachable.assign(n, 0);
    std::vector<std::uint8_t> mask(n);
    for (std::size_t k = 0; k < starts_.size(); ++k) {
      for (std::size_t i = 0; i < n; ++i) mask[i] = region_[i] == static_cast<int>(k);
      const std::vector<std::uint8_t> reach = coverage::reachableCells(world_, {starts_[k]}, mask);
      for (std::size_t i = 0; i < n; ++i) reachable[i] |= reach[i];
    }
  } else {
    reachable = coverage::reachableCells(world_, starts_);
  }
  return static_cast<int>(std::count(reachable.begin(), reachable.end(), 1));
}

void TeamOccupancy::finalView(std::vector<CellState>& states, std::vector<std::uint32_t>& visits) const {
  const int n = world_.geometry().cellCount();
  states.assign(static_cast<std::size_t>(n), CellState::Unknown);
  visits.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    const KnowledgeMap& m = maps_[regionsApart() ? static_cast<std::size_t>(region_[static_cast<std::size_t>(i)]) : 0];
    states[static_cast<std::size_t>(i)] = m.state(i);
    visits[static_cast<std::size_t>(i)] = m.visits(i);
  }
}

}  // namespace rover::coverage
