#pragma once
// What every planner returns, in a planner-neutral shape the server, CLI and exports read:
// named metrics, one track per rover in the local frame, and named curves.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/planning/outcomes.hpp"

namespace rover {

struct Metric {
  std::string key;
  double value = 0;
  std::string unit;  // "" when dimensionless
};

// One sample of a rover's motion as the planner knows it (the exports' CSV rows). NaN where the
// planner has no such quantity. Units inside: radians, metres, seconds.
struct TrackSample {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  double time = kNone;                 // s from the mission start
  Eigen::Vector2d position{0, 0};      // local frame, metres
  double heading = kNone;              // rad, counter-clockwise from east
  double roll = kNone, pitch = kNone;  // rad, as terrain::attitudeAt
  double speed = kNone;                // m/s over the ground
  double elevation = kNone;            // m, terrain height under the rover
};

struct Track {
  int rover = 0;
  std::vector<Eigen::Vector2d> points;  // local frame, metres
  std::vector<Metric> metrics;
  // A planner that models localisation error (coverage): `points` are the true positions and
  // these, one per point, where the rover believed it was; empty otherwise.
  std::vector<Eigen::Vector2d> believed;
  // Every sample of the motion when the planner has a clock (team: the simulator's 10 Hz
  // samples, denser than `points`); empty when its steps are grid moves (coverage: the exports
  // derive heading, attitude and height per point from the DEM, core/planning/ground_sample.hpp).
  std::vector<TrackSample> samples;
};

// A team route's target in visiting order and what became of the legs that served it.
struct RouteTarget {
  int index = 0;
  Eigen::Vector2d position{0, 0};  // local frame, the target cell's centre
  TargetStatus status = TargetStatus::Skipped;
  int reached = 0, shortLegs = 0, skipped = 0, noSlot = 0;  // legs, one per rover
};

struct Series {
  std::string key;  // e.g. "coverage_vs_moves"
  std::string xLabel, yLabel;
  std::vector<double> x, y;
};

// A polyline to draw (e.g. the team route, a rover's planned path); rover −1 = the team.
struct Polyline {
  std::string key;
  int rover = -1;
  std::vector<Eigen::Vector2d> points;  // local frame, metres
};

// Something the user must be told about (core/planning/outcomes.hpp lists the kinds), with where
// and when.
struct Incident {
  IncidentKind kind = IncidentKind::Collision;
  int rover = 0;
  int other = -1;  // the other rover of a collision
  double time = 0;  // s from the mission start
  Eigen::Vector2d position{0, 0};
  double value = 0;  // collision: the closest distance, m
  std::string note;
  std::int64_t step = -1;  // a planner without a clock (coverage's bump): the step, else -1
  // Why, as a short name the page groups incidents by (issue 27: 163 rows of one cause are one
  // group): the limit hit ("exceedance_limit", "safety_distance") or a leg's reason ("steep",
  // "no_path", …); "" when the planner gives none.
  std::string cause;
};

struct PlanResult {
  std::string planner;
  StopReason stopReason = StopReason::Cancelled;
  bool cancelled = false;
  std::vector<Metric> metrics;
  std::vector<Track> tracks;
  std::vector<Series> series;
  std::vector<Polyline> overlays;
  std::vector<Incident> incidents;
  std::vector<RouteTarget> targets;  // team planners: the route's targets; empty otherwise
  // What the planner took for granted that the user did not say, e.g. {"body", "mars"}.
  std::vector<std::pair<std::string, std::string>> assumptions;
  // Non-empty: the run completed, but with something the user must be told (a team mission's
  // short/skipped legs, unreachable ground, collisions…), one line each.
  std::vector<std::string> warnings;

  // The value of a metric; throws NotFound if the planner did not report it.
  double metric(const std::string& key) const;
};

}  // namespace rover
