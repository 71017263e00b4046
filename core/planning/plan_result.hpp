#pragma once
// What every planner returns, in a planner-neutral shape the server, CLI and exports read:
// named metrics, one track per rover in the local frame, and named curves.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace rover {

struct Metric {
  std::string key;
  double value = 0;
  std::string unit;  // "" when dimensionless
};

struct Track {
  int rover = 0;
  std::vector<Eigen::Vector2d> points;  // local frame, metres
  std::vector<Metric> metrics;
};

struct Series {
  std::string key;  // e.g. "coverage_vs_moves"
  std::string xLabel, yLabel;
  std::vector<double> x, y;
};

struct PlanResult {
  std::string planner;
  std::string stopReason;  // planner-defined, e.g. goal_reached, step_budget, cancelled
  bool cancelled = false;
  std::vector<Metric> metrics;
  std::vector<Track> tracks;
  std::vector<Series> series;

  // The value of a metric; throws NotFound if the planner did not report it.
  double metric(const std::string& key) const;
};

}  // namespace rover
