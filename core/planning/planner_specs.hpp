#pragma once
// What a planner says about itself, after OMPL's base::PlannerSpecs: the ground it plans on, where
// its rovers start when the caller places none, how its progress is measured, the metrics it
// reports and the stages a run goes through. The problem builder, admission, studies, the page's
// form and OpenAPI read this instead of comparing planner names.
#include <cstdint>
#include <string>
#include <vector>

#include "core/terrain/layers.hpp"

namespace rover {

// The part of PlanningProblem a planner reads.
enum class Ground {
  CoverageGrid,  // `world`: the map resampled to the planner's square cell, or a random obstacle grid
  DemAndPdm,     // `dem` at the map's own resolution and `pdm`, the probability to search, on its cells
};

// Where the rovers start when the caller places none (a study's runs, a run opened as a mission).
enum class StartPlacement {
  RandomCells,  // distinct random free cells of the grid's largest free region, seeded per run
  Formation,    // in formation around the map's centre
};

// How a run's progress is measured, in the series PlannerSpecs::progressSeries.
enum class ProgressMeasure {
  Coverage,   // the share of free cells visited against moves (a study reads the moves to a level)
  Detection,  // the PDM mass found against the distance per rover (a study reads it at distances)
};

struct MetricInfo {
  std::string key;   // as in PlanResult::metrics
  std::string unit;  // "" when dimensionless
  std::string doc;   // what it measures, and when it is reported if not always
};

struct StageInfo {
  std::string name;
  std::string doc;
};

struct PlannerSpecs {
  Ground ground = Ground::CoverageGrid;
  StartPlacement starts = StartPlacement::RandomCells;
  ProgressMeasure progress = ProgressMeasure::Coverage;
  std::string progressSeries;  // the PlanResult::series key of the progress curve
  // A run takes seconds (a simulated mission), not milliseconds: a sweep shows progress per run and
  // its summary keeps the timings, which are then a finding.
  bool secondsPerRun = false;
  std::vector<MetricInfo> metrics;  // the run's metrics (PlanResult::metrics)
  std::vector<StageInfo> stages;    // what a run does, in order
};

// How a planner's ground is laid on a map, resolved from its parameters (cheap: no grid is built).
struct MapGround {
  Ground kind = Ground::CoverageGrid;
  double cell = 0;                          // CoverageGrid: the square cell, m
  terrain::TraversabilityParams traversal;  // CoverageGrid: what makes a cell an obstacle
};

// What a mission costs in memory, estimated before it is queued, as an upper bound of its peak
// where a server runs it (its stream and result files included: the planner's outputs drive them).
// The planners' own code is the truth; each family's model is kept next to it and checked by
// tests/server/test_mission_peaks.cpp (measured peak <= 1.5 × estimate, per planner).
struct MemoryEstimate {
  std::uint64_t bytes = 0;
  std::string what;   // e.g. "9000000 coverage cells of 0.05 m, 1 rover"
  std::string field;  // the request field that drives it (params.coverage_cell, params.max_steps, map)
  // A mission whose bytes grow with its steps: bytes = fixedBytes + steps × bytesPerStep, so a
  // refusal can say which max_steps would fit. Zero when the estimate has no such form.
  std::uint64_t fixedBytes = 0, bytesPerStep = 0;
};

// Fixed per mission whatever the planner: its tables, the JSON of its spec and metrics, the stream.
constexpr std::uint64_t kMissionFixedBytes = 4ull << 20;

}  // namespace rover
