#pragma once
// One coverage rover as the engine's stages see it (core/coverage/coverage_planner.cpp): the pose
// the planner believes, which map it reads, whether it has stopped, and the move policy's memory.
// The true pose, when it differs, is the plant's (core/coverage/plant.hpp).
#include <cstddef>
#include <vector>

#include "core/coverage/coverage_planner.hpp"

namespace rover::coverage {

struct CoverageRover {
  int id = 0;
  int cell = 0;     // flat index of the believed cell
  int heading = 0;  // direction 0..7
  int mapId = 0;
  bool done = false;
  StopReason doneReason = StopReason::GoalReached;
  // Obstacle circumnavigation (paper 002 §2.2): the line being followed when an obstacle blocked
  // it, and where; the contour is followed with the obstacle on the right until the line is
  // regained.
  bool circling = false;
  int lineDir = 0;
  int lineOrigin = 0;
  int circleSteps = 0;
  int abandonedOrigin = -1;
  // Frontier mode: the known path being walked to the nearest unexplored cell.
  std::vector<int> plan;
  std::size_t planPos = 0;
};

}  // namespace rover::coverage
