#pragma once
// Ground truth for myopic coverage (SPEC §1): a grid of free/obstacle cells and, optionally,
// heights. Rovers never read this directly except through sensing.
#include <cstdint>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/planning/keep_out.hpp"

namespace rover::coverage {

struct World {
  Raster<std::uint8_t> obstacles;  // 1 = obstacle
  Raster<double> heights;          // metres; empty() = flat ground

  const GridGeometry& geometry() const { return obstacles.geometry; }
  bool isObstacle(int index) const { return obstacles.at(index) != 0; }
  bool hasHeights() const { return !heights.empty(); }
  double height(int index) const { return hasHeights() ? heights.at(index) : 0.0; }
  int obstacleCount() const;
  int freeCount() const { return geometry().cellCount() - obstacleCount(); }
};

// Keep-out zones as obstacles (core/planning/keep_out.hpp): every cell any part of which lies in a
// zone. Returns how many free cells it turned into obstacles.
int addKeepOut(World& world, const KeepOut& keepOut);

// Checks that the grid is usable for coverage (square cells, at least 2×2, heights finite and of
// the same size); throws InvalidInput naming the field otherwise.
void validateWorld(const World& world);

struct WorldParams {
  int rows = 60;
  int cols = 60;
  double cellSize = 1.0;           // metres
  double obstacleFraction = 0.05;  // of all cells, placed uniformly at random
  std::uint64_t seed = 1;
  // Paper 002 §3.2 forbids free regions sealed off by obstacles for its single-rover study; the
  // default allows them (as on real terrain) and the planners report them as unreachable.
  bool allowSealed = true;
};

// Random obstacle world. With allowSealed = false, obstacles are placed one at a time in random
// order and a placement is skipped when it could split the free space (local 8-ring test, below),
// so every free cell stays reachable; the obstacle count may then fall short of the target on dense
// maps.
World generateWorld(const WorldParams& params);

// Free cells 8-connected to any of `starts` (flat indices). Diagonal moves between two obstacles
// that touch at a corner are allowed, as in papers 000/002 where all 8 neighbours are candidates.
// `allowed`, when non-empty, restricts the flood to cells where allowed[i] != 0 (a Voronoi region).
std::vector<std::uint8_t> reachableCells(const World& world, const std::vector<int>& starts,
                                         const std::vector<std::uint8_t>& allowed = {});

// Labels 8-connected free components; returns the label per cell (-1 for obstacles) and the
// cell count per label.
std::vector<int> freeComponents(const World& world, std::vector<int>& sizes);

}  // namespace rover::coverage
