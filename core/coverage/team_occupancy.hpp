#pragma once
// Who is where in a coverage team (paper 002 §2.3): the rover holding each cell, the maps the
// rovers read (one shared map for an overlap team, one per Voronoi region), and the free cells
// the team can reach. A stage of the coverage engine (core/coverage/coverage_planner.cpp).
#include <cstdint>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/knowledge_map.hpp"
#include "core/coverage/world.hpp"

namespace rover::coverage {

class TeamOccupancy {
 public:
  static constexpr int kNoRover = -1;

  // Checks the starts (1..kMaxRovers, inside the grid, free, a heading 0..7, one rover a cell;
  // throws InvalidInput naming rovers[K]) and lays out the maps: Voronoi regions go to the
  // nearest start (Euclidean, in cells; ties to the lower rover index).
  TeamOccupancy(const World& world, const std::vector<StartCell>& starts, TeamMode mode);

  int occupant(int cell) const { return occupant_[static_cast<std::size_t>(cell)]; }
  bool isFree(int cell) const { return occupant(cell) == kNoRover; }
  void move(int rover, int from, int to) {
    occupant_[static_cast<std::size_t>(from)] = kNoRover;
    occupant_[static_cast<std::size_t>(to)] = rover;
  }
  const std::vector<int>& occupants() const { return occupant_; }
  const int* occupantData() const { return occupant_.data(); }

  int mapIdOf(int rover) const { return maps_.size() > 1 ? rover : 0; }
  KnowledgeMap& map(int mapId) { return maps_[static_cast<std::size_t>(mapId)]; }
  const KnowledgeMap& map(int mapId) const { return maps_[static_cast<std::size_t>(mapId)]; }
  const std::vector<KnowledgeMap>& maps() const { return maps_; }
  bool regionsApart() const { return maps_.size() > 1; }

  int visitedTotal() const {
    int v = 0;
    for (const auto& m : maps_) v += m.visitedCount();
    return v;
  }
  // An overlap team's goal on its shared map (Voronoi rovers stop one by one instead).
  bool teamGoalReached(double goal) const { return maps_.size() == 1 && maps_[0].goalReached(goal); }

  // Free cells the rovers can reach, each within its own region (8-connected, world.hpp). When
  // `visitedTrulyReached` cells were truly entered by moves and they are every free cell, that is
  // the answer without a flood fill (a run to full coverage, the common case of a study).
  int reachableCells(int visitedTrulyReached) const;
  // Owning rover per cell for Voronoi, empty for overlap.
  std::vector<int> takeRegion() { return std::move(region_); }
  // The team's view of the grid: each cell from the map that owns it.
  void finalView(std::vector<CellState>& states, std::vector<std::uint32_t>& visits) const;

 private:
  const World& world_;
  std::vector<int> starts_;
  std::vector<int> occupant_;
  std::vector<KnowledgeMap> maps_;
  std::vector<int> region_;
};

}  // namespace rover::coverage
