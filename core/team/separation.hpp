#pragma once
// Separation between rovers on the team's shared 10 Hz clock (SPEC §3.4): the traffic table
// behind the coordinator's check of each try, and the plan's final check (checkSeparation).
// Every trajectory starts at t = 0 with one sample per period, so "the same time" is "the same
// sample index"; before its
// first sample a rover waits there, after its last it is parked there (parked rovers are
// obstacles, ours where the paper is silent).
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "core/planning/rover_limits.hpp"
#include "core/team/rover_sim.hpp"

namespace rover::team {

// Two rovers closer than the safety distance.
struct Conflict {
  int rover = 0;  // the lower-priority rover
  int other = 0;  // the higher-priority rover
  double time = 0;        // s, first sample of the episode
  std::size_t index = 0;  // its sample index on the shared clock (time = index × period)
  double duration = 0;    // s, until the pair is apart again
  double distance = 0;    // m, the smallest distance in the episode
  Eigen::Vector2d position{0, 0};       // the rover, at `time`
  Eigen::Vector2d otherPosition{0, 0};  // the other rover, at `time`
};

// Position at sample index i: the first sample before the start, the last after the end.
// The trajectory must have a sample.
Eigen::Vector2d positionAtIndex(const Trajectory& t, std::size_t i);

// The committed trajectories of the higher-priority rovers read as a reservation table on the
// shared clock (ours; cooperative A*'s reservation table, Silver 2005, and SIPP's collision
// intervals, Phillips & Likhachev 2011, hold the same information per cell):
// the coordinator asks it, for every delay of every try, whether a rover at these positions from
// this sample index on comes closer than the safety distance to any of them; the rovers not
// planned yet stand at their starts meanwhile (issue 25). Positions are packed
// per rover and boxed per block of kBlock samples, so a query skips every block farther than the
// safety distance from the rover's own block — a hybrid mission's 56 000-sample tails and 61 start
// delays per try made the sample-by-sample scan a third of its sequential time. The answer is the
// scan's exactly: the first sample index with a conflict, and at it the first rover by index. Memory: 16 bytes per sample plus 32 per block of each rover.
class TrafficTable {
 public:
  static constexpr std::size_t kBlock = 16;
  static constexpr std::size_t kMaxRovers = planning::kMaxRovers;
  TrafficTable(double safety, double period) : safety_(safety), period_(period) {}
  // Appends the next rover (its trajectory must have a sample; at most kMaxRovers). A rover not
  // planned yet is added as the one sample of its start: standing there from t = 0 (issue 25).
  void add(const Trajectory& t);
  // Rover `rover`'s trajectory replaces what the table held for it (its start, standing).
  void replace(int rover, const Trajectory& t);
  int rovers() const { return static_cast<int>(rovers_.size()); }
  // The sample index after the longest trajectory's last: every rover is parked from then on.
  std::size_t end() const { return end_; }
  // Queries never compare `rover` with its own entry.
  // The first conflict of `rover` standing at `p` over sample indices [from, to).
  std::optional<Conflict> standing(int rover, const Eigen::Vector2d& p, std::size_t from,
                                   std::size_t to) const;
  // The first conflict of `rover` driving: sample m of `samples` at index `from + m`.
  std::optional<Conflict> driving(int rover, std::span<const TrajectorySample> samples,
                                  std::size_t from) const;

 private:
  struct Box {
    double x0, y0, x1, y1;
    static Box of(const Eigen::Vector2d& p) { return {p.x(), p.y(), p.x(), p.y()}; }
    void extend(const Eigen::Vector2d& p) {
      x0 = std::min(x0, p.x());
      y0 = std::min(y0, p.y());
      x1 = std::max(x1, p.x());
      y1 = std::max(y1, p.y());
    }
  };
  struct Track {
    std::vector<Eigen::Vector2d> at;  // position per sample index
    std::vector<Box> boxes;           // per block of kBlock indices
  };
  // Scans indices [from, from + count) of one block, the rover at `pos(m)` with box `box`.
  template <class Pos>
  std::optional<Conflict> scanBlock(int rover, std::size_t from, std::size_t count, const Box& box,
                                    const Pos& pos) const;
  Box boxAt(const Track& t, std::size_t block) const;
  double safety_, period_;
  std::vector<Track> rovers_;
  std::size_t end_ = 0;
};

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
