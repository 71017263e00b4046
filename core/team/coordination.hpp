#pragma once
// Prioritised multi-rover planning (paper 001 §3.6 and fig. 8, SPEC §3.4). Rovers are taken in
// priority order (index 0 first). Each rover's task is a list of legs; each leg is planned with
// RRT* (terrain_rrt) or given as fixed points (the hybrid mission's coverage moves), simulated
// (rover_sim) from where the rover really stopped, and checked sample by sample in time against
// every higher-priority rover's committed trajectory. A leg that comes closer than the safety
// distance is planned again with a new seed, up to a bound; then the rover waits and tries again;
// then it skips the leg. Whatever is left is reported: a returned plan is collision-free or lists
// exactly where it is not (`conflicts`).
// This header holds the parameters, the tasks and the result; the stages are apart:
// route_generator → task_builder → coordinator (taking a leg_planner and a leg_simulator, the
// policy on conflicts a parameter) → team_metrics; separation.hpp is the one distance check.
//
// Choices made here where the paper is silent (each repeated where it is implemented):
// - Every rover starts at t = 0 and all trajectories share one 10 Hz clock, so "the same time" is
//   "the same sample index" and a check is one distance per sample and rover.
// - A rover is present before it starts and after it ends (parked where it stopped): later rovers
//   are checked against parked ones, and a rover's own parking spot is checked against every
//   higher-priority rover still moving after it has finished.
// - A finished rover that cannot park out of a higher-priority rover's way (no spot at a map edge,
//   or out of moves) moves aside from an earlier stop, else stops at the latest end of a move
//   where it may stand for good, its start at worst; the moves after it are undone (issue 25).
//   Every committed sample is checked against the traffic table, so no two rovers come closer
//   than the safety distance, by construction.
// - A retry keeps out of a disc around where the higher-priority rover was at each earlier
//   conflict (KeepOutZone): with only a new seed, RRT* converges to the same straight line on
//   open ground and a head-on pair could never separate.
// - A conflict within the first second of a try cannot be dodged by another path (the rover has
//   barely moved): in paper mode the re-plans are skipped and the rover goes straight to waiting.
// - The rover stops at the end of each leg (it looks at its target) and starts the next at rest.
// - Legs are planned ahead in parallel from their nominal start (the previous leg's goal), which
//   is within the acceptance radius of where the rover stops; a leg whose rover ended elsewhere
//   (a skip, a short leg) is planned again from the real position.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/common/enum_names.hpp"
#include "core/grid/raster.hpp"
#include "core/team/rover_sim.hpp"
#include "core/team/separation.hpp"
#include "core/team/terrain_rrt.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

// One leg of a rover's task.
struct Leg {
  Eigen::Vector2d goal{0, 0};         // local frame; RRT* goal (target centre + formation slot)
  std::vector<Eigen::Vector2d> via;   // non-empty: follow these points as given; goal = via.back()
  int target = -1;                    // route target the leg serves (-1: none)
};

struct RoverTask {
  Pose start;
  std::vector<Leg> legs;
};

// The team's RRT* defaults: paper 001's, except (ours)
// - the planning attitude limit, 14° — one degree under the 15° at which exceedances are counted.
//   The simulated rover cuts corners and turns at vertices; with no margin it exceeded 15° on
//   ~1e-4 of its samples.
// - an iteration cap of 15 000 (12× the vertex target): a start in a dead end cannot grow its tree
//   to 1250 vertices, and the generic 100 000 made such missions take minutes for the same result.
inline RrtParams teamRrtDefaults() {
  RrtParams r;
  r.attitudeLimit = 14.0 * std::numbers::pi / 180.0;
  r.maxIterations = 15000;
  return r;
}

// How conflicts between rovers are resolved and how a leg is planned.
enum class CoordinationMode {
  // Ours (the default): each leg's RRT* runs in a corridor around a guide path on the traversal
  // lattice (falling back to the guide itself), and a try that comes too close to a higher-
  // priority rover is first delayed — the same path started later, checked at 10 Hz against
  // every committed trajectory (a reservation check in time) — and only re-planned with a
  // keep-out zone when no delay up to max_waits × wait_step clears it.
  Timed,
  // Paper 001 fig. 8 as SPEC §3.4 reads it: RRT* in the start/goal box grown by the clearance,
  // re-planned with a new seed on each conflict, then waits, then the target is skipped.
  Paper,
};

// The most start delays timed mode tries per try (CoordinationParams::validate).
inline constexpr int kMaxStartDelays = 1200;

struct CoordinationParams {
  CoordinationMode mode = CoordinationMode::Timed;  //                          [coordination]
  // m, Timed: RRT* samples within this distance of the guide path (ours).    [corridor_radius]
  double corridorRadius = 2.0;
  // s, Timed: the delays tried before a re-plan are multiples of this (ours).      [delay_step]
  double delayStep = 0.5;
  RrtParams rrt = teamRrtDefaults();
  TerrainCostWeights weights;
  RoverModel model;
  ControllerParams controller;
  SlipParams slip;
  double safetyDistance = 1.0;  // m, SPEC §3.4                              [safety_distance]
  int maxReplans = 20;          // re-plans with a new seed per leg, SPEC §3.4    [max_replans]
  double waitStep = 5.0;        // s, each wait adds this much (ours)            [wait_step]
  int maxWaits = 6;             // waits before the leg is skipped (ours)         [max_waits]
  // m, radius of the disc a retry keeps out of around each conflict (ours): the safety distance
  // plus half a metre of margin for the simulated rover's deviation from its path.
  double keepOutRadius = 1.5;  //                                               [keep_out_radius]
  // RRT* calls chained in one leg when a tree ends short of its goal (a long first leg, a goal
  // behind a ridge), each from where the last one ended (ours).                 [max_pieces]
  int maxPieces = 6;
  // s a rover is checked standing at the end of each leg (ours): it stops there and needs a few
  // seconds to get going again, so a leg ending where a higher-priority rover passes a moment
  // later is refused then, while waiting can still help, not on the next leg. Both modes use
  // it; in timed mode it is also the time a stopped rover has to step aside when its next leg
  // finds no clear try (coordinator.cpp, ConflictPolicy::recovers).           [dwell_check]
  double dwellCheck = 10.0;
  // rad; a simulated try whose |roll| or |pitch| goes above this is refused and planned again like
  // a conflict, keeping out of half a metre around the spot (ours; 0 = off); when no try is within
  // it the leg ends short. Only a move out of a collision (parking, timed mode's step aside)
  // may exceed it, and that is reported.                                                          [attitude_check]
  double attitudeCheck = kDefaultAttitudeLimit;
  // Threads the caller grants (the look-ahead planning, the lattice); 0 = all cores. The server
  // gives each mission its share so missions in parallel do not oversubscribe the machine.
  unsigned threads = 0;

  // Throws InvalidParameter with the key (and those of the nested structs).
  void validate() const;
};

enum class LegStatus {
  Reached,  // the rover entered its goal's acceptance circle
  Short,    // it ended away from its goal: no path (unreachable goal, tree short after every piece)
  Skipped,  // given up by the wait-then-skip fallback, or the goal is not on passable ground
};
// Why a leg that did not reach its goal ended (None for a reached leg).
enum class LegReason {
  None,
  InvalidGoal,      // the goal is not on ground a rover may stop on
  NoPath,           // no path to the goal (RRT* and, Timed, the guide), or no progress
  Steep,            // every try tilts past the attitude check
  Conflict,         // every try and every delay comes too close to a higher-priority rover
  PiecesExhausted,  // max_pieces RRT* pieces and still short of the goal
  KeepOut,          // every try's simulated rover entered a keep-out zone's cells
};

struct LegRecord {
  int rover = 0;
  int leg = 0;
  int target = -1;
  LegStatus status = LegStatus::Reached;
  LegReason reason = LegReason::None;
  int replans = 0;      // planning attempts after the first, over all pieces
  int waits = 0;        // waits before the accepted try (Timed: pieces started late)
  double waitTime = 0;  // s spent waiting before accepted pieces
  int pieces = 0;       // accepted path pieces
  double startTime = 0;  // s
  double endTime = 0;    // s
  std::string note;      // why it was skipped or ended short
};

// Told about each accepted piece as soon as it is committed (the server streams it).
class CoordinationObserver {
 public:
  virtual ~CoordinationObserver() = default;
  // `path`: the waypoints the rover follows (its current position first); `samples`: the 10 Hz
  // samples this piece adds to its trajectory (waits included).
  virtual void pieceAccepted(int rover, std::span<const Eigen::Vector2d> path,
                             std::span<const TrajectorySample> samples) {
    (void)rover;
    (void)path;
    (void)samples;
  }
  virtual void legDone(const LegRecord& leg, int legsDone, int legsTotal) {
    (void)leg;
    (void)legsDone;
    (void)legsTotal;
  }
};

struct CoordinationResult {
  std::vector<Trajectory> trajectories;             // per rover; samples at k × period from 0
  std::vector<std::vector<Eigen::Vector2d>> paths;  // per rover: accepted waypoints, in order
  std::vector<LegRecord> legs;                      // rover-major, in task order
  std::vector<Conflict> conflicts;                  // left in the plan; empty = collision-free
  int replans = 0;
  int waits = 0;
  int rrtCalls = 0;
  bool cancelled = false;
};

// Plans, simulates and coordinates the team with the terrain stages of `params.mode`
// (coordinator.hpp): Paper, the boxed RRT* planner and the paper's policy; Timed, the guided
// planner and the timed policy; the rover simulator on `dem` for both. `classes` holds terrain::TerrainClass values on the
// DEM's grid. `seed` drives every RRT* call (deriveSeed per rover, leg, piece and attempt) and the
// slip noise, so the result is the same for a seed whatever the thread count. Throws
// InvalidParameter for bad parameters and InvalidInput naming rovers[k] for a start off the map.
// `lattice` (Timed mode; built from the DEM here when null) must be built on the same DEM and
// classes with the RRT*'s attitude limit.
CoordinationResult coordinate(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                              const std::vector<RoverTask>& tasks,
                              const CoordinationParams& params, std::uint64_t seed,
                              CoordinationObserver* observer = nullptr,
                              const CancelToken* cancel = nullptr,
                              const TraversalLattice* lattice = nullptr);

// `params` with EdgeEvaluation::Auto made what coordinate() uses: Sampled (paper 001's) in the
// paper mode, Patch (the exact maxima, issue 25) in the timed mode.
CoordinationParams resolveEvaluation(CoordinationParams params);

// The lattice coordinate() uses for these parameters (attitude limit, edge resolution, eq. 9).
TraversalLattice makeLattice(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                             const CoordinationParams& params);

}  // namespace rover::team

// The names of the values above (enum_names.hpp).
namespace rover {
template <>
struct EnumNames<team::CoordinationMode> {
  static constexpr std::array<EnumName<team::CoordinationMode>, 2> table{{
      {team::CoordinationMode::Timed, "timed"},
      {team::CoordinationMode::Paper, "paper"},
  }};
};
template <>
struct EnumNames<team::LegReason> {
  static constexpr std::array<EnumName<team::LegReason>, 7> table{{
      {team::LegReason::None, "none"},
      {team::LegReason::InvalidGoal, "invalid_goal"},
      {team::LegReason::NoPath, "no_path"},
      {team::LegReason::Steep, "steep"},
      {team::LegReason::Conflict, "conflict"},
      {team::LegReason::PiecesExhausted, "pieces_exhausted"},
      {team::LegReason::KeepOut, "keep_out"},
  }};
};
}  // namespace rover
