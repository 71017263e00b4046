#pragma once
// Myopic coverage path planning for one rover or a team (SPEC §1): papers 002 (Laîné & Yoshida
// 2019, eq. 1, Algorithm 1, §2.3) and 000 (Santra et al., eq. 3 cost with heights, eq. 5 energy),
// plus our `frontier` mode.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/knowledge_map.hpp"
#include "core/coverage/world.hpp"
#include "core/planning/events.hpp"
#include "core/planning/outcomes.hpp"

namespace rover::coverage {

struct StartCell {
  int cell = 0;     // flat index
  int heading = 0;  // direction 0..7 (0 = east, counter-clockwise)
};

// `count` distinct random free cells of the largest free component (a rover dropped into a sealed
// pocket could never move) with random headings, from `seed`.
std::vector<StartCell> randomStarts(const World& world, int count, std::uint64_t seed);

// Why a run stopped: the planner-neutral enum (core/planning/outcomes.hpp), of which coverage uses
// GoalReached, NothingLeft, StepBudget and Cancelled.
using StopReason = rover::StopReason;

struct RoverTrack {
  std::vector<int> cells;       // start cell, then one entry per move
  std::vector<float> pitchDeg;  // one entry per move: atan(|Δh| / horizontal distance)
  std::int64_t moves = 0;
  std::int64_t waits = 0;  // steps with no legal move (boxed in by team mates)
  int revisits = 0;        // moves into a cell already visited
  double distanceM = 0;    // horizontal; diagonal moves are √2 cells
  double energyJ = 0;      // paper 000 eq. 5
  double maxPitchDeg = 0;
  // Localisation error (params.localisation.active(), core/coverage/dead_reckoning.hpp); empty
  // otherwise. `cells` above are then the believed cells; energy and pitch are the true motion's.
  std::vector<Eigen::Vector2d> truePoints;      // true position at the start and after each move
  std::vector<Eigen::Vector2d> believedPoints;  // believed position, likewise
  std::vector<float> errorM;                    // |true − believed| after each move, m
  int bumps = 0;
  int loopClosures = 0;
  double maeM = 0;  // mean of errorM (paper 000 eq. 6 with its 1/N)
};

struct CurvePoint {
  std::int64_t step = 0;
  std::int64_t moves = 0;  // all rovers' moves so far
  int visited = 0;         // distinct cells visited by the team so far
  int trueVisited = 0;     // localisation error: distinct cells truly stood in (else = visited)
};

// A move into a true obstacle (localisation error): the rover stayed and marked `cell` an obstacle.
struct Bump {
  int rover = 0;
  std::int64_t step = 0;
  int cell = 0;                   // the believed target cell, now an obstacle in the map
  Eigen::Vector2d truePosition;   // where the rover truly stands (local frame)
  bool offField = false;          // the move would have left the field
};

struct CoverageMetrics {
  double coverage = 0;           // visited / free cells (ground truth)
  double coverageReachable = 0;  // visited / free cells the rovers can reach
  std::int64_t moves = 0;        // sum over rovers
  std::int64_t makespan = 0;     // moves of the busiest rover
  std::int64_t steps = 0;
  double pathLengthRatio = 0;  // moves / n (paper 002 eq. 2; the sum over rovers for a team)
  double makespanRatio = 0;    // makespan / n
  double distanceM = 0;
  double energyJ = 0;
  double maxPitchDeg = 0;
  int revisits = 0;
  int cells = 0;
  int freeCells = 0;
  int reachableCells = 0;
  int unreachableCells = 0;  // free cells no rover can reach (sealed off, or outside its region)
  int visitedCells = 0;
  // Localisation error (core/coverage/dead_reckoning.hpp); `coverage` above is then the believed
  // coverage, the planner's own map.
  bool localisation = false;
  double trueCoverage = 0;      // distinct cells truly stood in / free cells
  int trueVisitedCells = 0;
  double maeM = 0;              // over every move of every rover
  double maxErrorM = 0;
  double finalErrorM = 0;       // mean over rovers of the last error
  double mapAccuracy = 0;       // mapped cells whose obstacle/free state is true / mapped cells
  int mappedCells = 0;
  int bumps = 0;
  int loopClosures = 0;
};

struct CoverageResult {
  StopReason stop = StopReason::StepBudget;
  CoverageMetrics metrics;
  std::vector<RoverTrack> rovers;
  std::vector<CurvePoint> curve;  // one point per step, the first at step 0
  std::vector<int> region;        // Voronoi: owning rover per cell; empty for overlap
  std::vector<CellState> finalStates;
  std::vector<std::uint32_t> finalVisits;
  std::vector<Bump> bumps;  // the first kMaxBumpRecords; metrics.bumps counts them all
};

inline constexpr std::size_t kMaxBumpRecords = 1000;

// Runs the planner to its stop rule. Throws rover::Error for a bad world, parameters or start
// (outside the grid, on an obstacle, two rovers on one cell). `sink` and `cancel` may be null.
CoverageResult runCoverage(const World& world, const std::vector<StartCell>& starts,
                           const CoverageParams& params, EventSink* sink = nullptr,
                           const CancelToken* cancel = nullptr);

// Moves (of all rovers) at which the team first reached `fraction` of the reachable free cells,
// read from the run's own curve; -1 if never reached.
std::int64_t movesToReach(const CoverageResult& result, double fraction);

}  // namespace rover::coverage
