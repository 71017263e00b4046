#pragma once
// The rover's body in a coverage run, a stage of the coverage engine
// (core/coverage/coverage_planner.cpp): what it senses and where a commanded move truly takes it.
// Two plants, one interface: PerfectPlant, where the believed pose is the true one (papers
// 000/002's simulations), and the dead-reckoning plant of core/coverage/dead_reckoning.hpp, where
// odometry noise, slip and loop closure keep the two apart. The engine never asks which it has.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/coverage_rover.hpp"
#include "core/coverage/recorder.hpp"
#include "core/coverage/team_occupancy.hpp"
#include "core/coverage/world.hpp"
#include "core/planning/events.hpp"

namespace rover::coverage {

// How a commanded move ended.
enum class Drive {
  Moved,    // the rover is in its next believed cell (the engine books the move)
  Bumped,   // it hit a true obstacle, stayed, and marked the cell an obstacle in its map
  Blocked,  // a team mate truly stands where it would end: it waits
};

// The true side of a move that happened: horizontal metres driven and metres climbed, for
// energy and pitch.
struct Motion {
  double horizontal = 0;
  double dh = 0;
};

class Plant {
 public:
  virtual ~Plant() = default;
  // Whether the believed pose is always the true one: then the truly visited cells are the
  // team's visited cells, which the engine reads once a step instead of asking trueVisited().
  bool poseIsTrue() const { return poseIsTrue_; }
  // Myopic, omnidirectional sensing: every cell within Chebyshev radius R (SPEC §1 step 1) is
  // written into the rover's map as the plant sees it.
  virtual void sense(const CoverageRover& r) = 0;
  // Drives `r` from its believed cell toward the neighbouring cell `next`, in direction `dir`
  // (neighbourDir from the cell to `next`), at `step`; on Moved, `motion` is what truly happened.
  virtual Drive drive(CoverageRover& r, int next, int dir, std::int64_t step, Motion& motion) = 0;
  // After the engine booked a Moved drive (map, occupancy and heading updated).
  virtual void arrived(CoverageRover& r) = 0;
  // Whether a rover its own map walls in stops for good (its map can then never open again).
  virtual bool stopsWalledIn() const = 0;
  // Distinct cells truly stood in so far (the team's visited cells for a perfect plant).
  virtual int trueVisited() const = 0;
  // Of the visited cells, how many were truly reached by moves (all of them, or 0 when the
  // believed cells may be elsewhere): TeamOccupancy::reachableCells' shortcut.
  virtual int visitedTrulyReached() const = 0;
  virtual RoverPose pose(const CoverageRover& r) const = 0;
  // Adds the plant's metrics, tracks and incidents to a finished result.
  virtual void summarise(CoverageResult& result) const = 0;

 protected:
  explicit Plant(bool poseIsTrue) : poseIsTrue_(poseIsTrue) {}

 private:
  const bool poseIsTrue_;
};

// Senses around the believed cell what lies around the true cell (the same cell for a perfect
// pose): rows and columns clipped to the grid once, not tested per cell.
void senseWindow(const World& world, int radius, KnowledgeMap& map, int believedCell, int trueCell,
                 Recorder& recorder);

// The dead-reckoning plant (core/coverage/dead_reckoning_plant.cpp): sets up each rover's
// odometry and true pose at its start.
std::unique_ptr<Plant> makeDeadReckoningPlant(const World& world, const CoverageParams& params,
                                              TeamOccupancy& team, Recorder& recorder,
                                              const std::vector<CoverageRover>& rovers);
// A perfect plant when params.localisation is inactive, else dead reckoning.
std::unique_ptr<Plant> makePlant(const World& world, const CoverageParams& params, TeamOccupancy& team,
                                 Recorder& recorder, const std::vector<CoverageRover>& rovers);

}  // namespace rover::coverage
