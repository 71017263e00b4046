#pragma once
// A rover's own map in myopic coverage (papers 002/000 §2): every cell starts Unknown, sensing
// writes Free/Obstacle, entering writes Visited and counts visits. Counts are kept incrementally;
// paper 002's Algorithm 1 recounts the whole map every step (lines 10–12), O(n) a step, which we
// avoid.
#include <cstdint>
#include <vector>

#include "core/grid/geometry.hpp"

namespace rover::coverage {

enum class CellState : std::uint8_t { Unknown = 0, Free = 1, Obstacle = 2, Visited = 3 };

class KnowledgeMap {
 public:
  // `region` (empty = whole grid): cells this map may hold and its rovers may enter (Voronoi).
  KnowledgeMap(const GridGeometry& g, std::vector<std::uint8_t> region = {});

  const GridGeometry& geometry() const { return geometry_; }
  CellState state(int i) const { return state_[i]; }
  std::uint32_t visits(int i) const { return visits_[i]; }
  bool inRegion(int i) const { return region_.empty() || region_[i] != 0; }
  // The same cells as raw arrays, for the engine's innermost loop (MovePolicy::costStep reads
  // eight neighbours a move; through the accessors the compiler reloads each vector per read).
  const CellState* stateData() const { return state_.data(); }
  const std::uint32_t* visitsData() const { return visits_.data(); }
  const std::uint8_t* regionData() const { return region_.empty() ? nullptr : region_.data(); }
  int regionCells() const { return regionCells_; }
  // Cells of the region still Unknown. Under a perfect pose a map never forgets, so at 0 sensing
  // can change nothing more (the last two thirds of a run to full coverage, spent revisiting).
  int unknownCells() const { return unknown_; }
  int visitedCount() const { return visited_; }
  int knownObstacles() const { return knownObstacles_; }

  // Writes the sensed truth into an Unknown cell; returns whether the map changed. Inline with
  // visit and goalReached: a coverage run calls them for every cell it senses and every move.
  bool sense(int i, bool obstacle) {
    if (state_[i] != CellState::Unknown) return false;
    state_[i] = obstacle ? CellState::Obstacle : CellState::Free;
    knownObstacles_ += obstacle;
    unknown_ -= inRegion(i);
    return true;
  }
  // sense() over `count` cells from `first`, `stride` apart (a row or column of a sensing window),
  // with the truth read from `obstacle`; `changed(i, state)` is told each cell that became known,
  // in order. The perfect-pose plant's per-move read: through sense() the compiler reloads every
  // array per cell (a sixth of a coverage study's instructions).
  template <class Changed>
  void senseLine(int first, int stride, int count, const std::uint8_t* obstacle, Changed&& changed) {
    CellState* const state = state_.data();
    const std::uint8_t* const region = region_.empty() ? nullptr : region_.data();
    int found = 0;
    for (int k = 0, i = first; k < count; ++k, i += stride) {
      if ((region && !region[i]) || state[i] != CellState::Unknown) continue;
      const bool isObstacle = obstacle[i] != 0;
      state[i] = isObstacle ? CellState::Obstacle : CellState::Free;
      found += isObstacle;
      --unknown_;
      changed(i, state[i]);
    }
    knownObstacles_ += found;
  }
  // sense() over the cells `centre + offsets[k]` (all in the grid), in order: the perfect plant's
  // read of the cells a one-cell move away from the border brings into range.
  template <class Changed>
  void senseAround(int centre, const std::vector<int>& offsets, const std::uint8_t* obstacle, Changed&& changed) {
    CellState* const state = state_.data();
    const std::uint8_t* const region = region_.empty() ? nullptr : region_.data();
    int found = 0;
    for (const int offset : offsets) {
      const int i = centre + offset;
      if ((region && !region[i]) || state[i] != CellState::Unknown) continue;
      const bool isObstacle = obstacle[i] != 0;
      state[i] = isObstacle ? CellState::Obstacle : CellState::Free;
      found += isObstacle;
      --unknown_;
      changed(i, state[i]);
    }
    knownObstacles_ += found;
  }
  // Enters a cell (it must not be an obstacle); returns whether it was visited before.
  bool visit(int i) {
    const bool before = visits_[i] > 0;
    if (!before) {
      ++visited_;
      unknown_ -= state_[i] == CellState::Unknown && inRegion(i);  // a start cell, before sensing
    }
    state_[i] = CellState::Visited;
    ++visits_[i];
    return before;
  }
  // A bump (core/coverage/dead_reckoning.hpp): the cell is an obstacle whatever the map held;
  // a cell believed visited no longer counts as visited. Returns whether the map changed.
  bool markObstacle(int i);
  // Paper 002 Algorithm 1 line 13 (with the printed `≤` read as `≥`, SPEC §1):
  // visited >= goal · (cells − known obstacles).
  // The count it needs is worked out again only when the known obstacles or the goal changed.
  bool goalReached(double goal) const {
    if (goal != goalOf_ || knownObstacles_ != obstaclesOf_) {
      goalOf_ = goal;
      obstaclesOf_ = knownObstacles_;
      needed_ = neededFor(goal);
    }
    return visited_ >= needed_;
  }

 private:
  int neededFor(double goal) const;

  GridGeometry geometry_;
  std::vector<std::uint8_t> region_;
  std::vector<CellState> state_;
  std::vector<std::uint32_t> visits_;
  int regionCells_ = 0;
  int unknown_ = 0;
  int visited_ = 0;
  int knownObstacles_ = 0;
  // goalReached's last answer's inputs and the visited count they need.
  mutable double goalOf_ = -1;
  mutable int obstaclesOf_ = -1;
  mutable int needed_ = 0;
};

}  // namespace rover::coverage
