#pragma once
// Separation between rovers on the team's shared 10 Hz clock (SPEC §3.4): the one routine behind
// the coordinator's check of each try and the plan's final check. Every trajectory starts at
// t = 0 with one sample per period, so "the same time" is "the same sample index"; before its
// first sample a rover waits there, after its last it is parked there (parked rovers are
// obstacles, ours where the paper is silent).
#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "core/team/rover_sim.hpp"

namespace rover::team {

// Two rovers closer than the safety distance.
struct Conflict {
  int rover = 0;  // the lower-priority rover
  int other = 0;  // the higher-priority rover
  double time = 0;        // s, first sample of the episode
  double duration = 0;    // s, until the pair is apart again
  double distance = 0;    // m, the smallest distance in the episode
  Eigen::Vector2d position{0, 0};       // the rover, at `time`
  Eigen::Vector2d otherPosition{0, 0};  // the other rover, at `time`
};

// Position at sample index i: the first sample before the start, the last after the end.
// The trajectory must have a sample.
Eigen::Vector2d positionAtIndex(const Trajectory& t, std::size_t i);

// The first of `others` closer than `safety` to a rover at `p` at sample index `index`
// (`rover` and the index of each of `others` in the span fill the Conflict).
std::optional<Conflict> conflictAt(std::span<const Trajectory> others, int rover, std::size_t index,
                                   const Eigen::Vector2d& p, double safety, double period);

// Every episode in which two rovers are closer than `safety` (compared at every sample index,
// parked rovers included), and the smallest distance between any two rovers over the mission.
// Throws InvalidInput on a trajectory without samples.
struct SeparationReport {
  std::vector<Conflict> conflicts;  // by time
  double minimumDistance = 0;       // m; +∞ with fewer than two rovers
  double minimumTime = 0;           // s
  int minimumPair[2] = {0, 0};
};
SeparationReport checkSeparation(const std::vector<Trajectory>& trajectories, double safety);

}  // namespace rover::team
