#pragma once
// What a planner reports while it runs (DESIGN.md: a plain event sink; the server turns events into
// WebSocket frames on its own strand, a planner thread never touches a socket). All positions are
// in the local frame of SPEC §0. Default implementations ignore the event, so a sink overrides only
// what it wants; a planner handed no sink builds no events at all.
#include <cstdint>
#include <span>
#include <string_view>

#include "core/planning/plan_result.hpp"

namespace rover {

// One cell of a planner's grid whose displayed state changed (state codes are the planner's own:
// coverage uses CellState).
struct CellUpdate {
  std::int32_t index = 0;  // row * cols + col
  std::uint8_t state = 0;
  std::uint32_t visits = 0;
};

struct RoverPose {
  int rover = 0;
  double x = 0;        // metres east of the lower-left corner
  double y = 0;        // metres north
  double heading = 0;  // radians counter-clockwise from east
  // A planner that models localisation error (coverage, core/coverage/dead_reckoning.hpp): x and
  // y are then the true position, and this is where the rover believes it is.
  bool hasBelief = false;
  double believedX = 0;
  double believedY = 0;
};

struct Progress {
  std::int64_t step = 0;
  double fraction = 0;  // 0..1 towards the run's goal
  double coverage = 0;  // fraction of free cells visited so far
  std::int64_t moves = 0;
  // Team missions (paper 001) run in two phases an operator wants told apart: planning, counted
  // in legs, then the replay of the plan, on the mission clock. Empty phase: a coverage run.
  enum class Phase { None, Planning, Replay };
  Phase phase = Phase::None;
  int legsDone = 0, legsTotal = 0;
  int replans = 0, waits = 0;        // so far, over all legs
  double missionTime = 0;            // s: the replay's clock
  double missionEnd = 0;             // s: when the last rover is done
};

// A point of an overlay polyline (local frame, metres).
struct Point2 {
  double x = 0;
  double y = 0;
};

class EventSink {
 public:
  virtual ~EventSink() = default;
  virtual void cellsChanged(std::span<const CellUpdate> cells) { (void)cells; }
  virtual void roverPoses(std::int64_t step, std::span<const RoverPose> poses) {
    (void)step;
    (void)poses;
  }
  virtual void progress(const Progress& p) { (void)p; }
  // A polyline drawn over the map: `kind` "route" (the team route, rover −1, replaces the last
  // one) or "path" (points appended to a rover's planned path, as each piece is accepted).
  virtual void overlay(std::string_view kind, int rover, std::span<const Point2> points) {
    (void)kind;
    (void)rover;
    (void)points;
  }
  // Metrics known before the run ends (the team planners report theirs once simulation is done).
  virtual void metrics(std::span<const Metric> metrics) { (void)metrics; }
  // Incidents as they are found (`complete` false: appended to those reported so far), or the
  // run's whole list, the same as PlanResult::incidents (`complete` true: it replaces them; the
  // planner's final word, e.g. once collisions are checked over the whole plan).
  virtual void incidents(std::span<const Incident> found, bool complete) {
    (void)found;
    (void)complete;
  }
};

}  // namespace rover
