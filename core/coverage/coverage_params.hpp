#pragma once
// Parameters of the myopic coverage planner (SPEC §1) with their documented defaults.
#include <cstdint>
#include <string>
#include <vector>

#include "core/planning/rover_range.hpp"
#include "core/common/params.hpp"
#include "core/coverage/cost_table.hpp"
#include "core/terrain/layers.hpp"

namespace rover::coverage {

enum class TeamMode { Overlap, Voronoi };  // paper 002 §2.3

// Paper 000 eq. 5 and its defaults for the CLOVER rover on the Moon.
struct EnergyModel {
  double massKg = 7.0;
  // m/s², the Moon (paper 000's CLOVER). On a map whose CRS names its body, the planner takes
  // that body's gravity instead unless the user gave one (issue 11).
  double gravity = 1.62;
  double rollingResistance = 0.15;  // μ
  double efficiency = 0.7;          // η, drive train
  double turnJoulesPerRad = 2.0;    // spot turn
};

// Localisation error (issue 15): odometry drift, the map it smears and loop closure; the model is
// documented where it is made, core/coverage/dead_reckoning.hpp. All zero / off by default: the
// rover then knows its pose exactly, as in papers 000/002's simulations.
struct LocalisationModel {
  double distanceNoisePct = 0.0;  // std of a move's travelled distance, % of the move
  double headingNoiseDeg = 0.0;   // std of the heading error added per move (a random walk), deg
  double slipPctPerDeg = 0.0;     // uphill shortfall of a move, % per degree of pitch
  bool loopClosure = false;
  double loopClosureKeep = 0.1;        // fraction of the pose error left after a loop closure
  std::int64_t loopClosureGap = 20;    // moves since the cell was last entered, at least
  std::uint64_t seed = 1;              // of the odometry noise
  // Whether the believed and the true pose are kept apart at all (any noise, or loop closure on).
  bool active() const {
    return distanceNoisePct > 0 || headingNoiseDeg > 0 || slipPctPerDeg > 0 || loopClosure;
  }
};

struct CoverageParams {
  TeamMode mode = TeamMode::Overlap;
  std::string pattern = "spiral";  // spiral | boustrophedon | custom
  std::vector<double> costTable;   // pattern = custom: 8 relative (+ 8 absolute) costs
  bool circumnavigate = false;
  bool frontier = false;
  int senseRadius = 1;        // Chebyshev radius, 1 or 2
  double coverage = 0.95;     // stop goal, fraction of n − O
  double alpha = 1.0;         // weight of static + visited cost (paper 000 eq. 3)
  double beta = 0.0;          // weight of |Δh| (paper 000 eq. 3)
  double mcVisited = 1.1;     // penalty per previous visit (paper 000: >= 1.1)
  std::int64_t maxSteps = 0;  // 0 = 20·n
  // Coverage grid cell on a DEM, metres; 0 = from the map: its own cell, or the smallest size
  // whose grid fits cellBudget (core/coverage/terrain_world.hpp). The planner itself runs on
  // whatever grid it is given; the server and CLI build it from the DEM with worldFromDem.
  double coverageCell = 0.0;
  // The default coverage cell keeps a DEM's grid within this many cells (an explicit coverage_cell
  // may give up to kMaxCoverageCells): 40 000 = 200 × 200 keeps a default run on the page's map
  // (150 m at 0.25 m) as quick as the paper-scale grids; larger maps get coarser default cells.
  std::int64_t cellBudget = 40'000;
  // A DEM pixel with a slope of this or more to a neighbour is impassable (SPEC §2).
  double impassableDeg = 15.0;
  EnergyModel energy;
  // What the operator states one rover can do (core/planning/rover_range.hpp); 0 = not stated.
  planning::RoverRange range;
  LocalisationModel localisation;
  // Not a user parameter: false for a study's metrics-only runs (PlanningProblem::metricsOnly),
  // whose results keep no per-move cells or pitch, so the recorder stores none.
  bool recordTracks = true;

  MotionCostTable table() const;
  // The traversability thresholds of impassableDeg (only the impassable class matters here).
  terrain::TraversabilityParams traversability() const;
  std::int64_t stepBudget(int cellCount) const {
    return maxSteps > 0 ? maxSteps : 20LL * cellCount;
  }
};

const ParamTable<CoverageParams>& coverageParamTable();
// Defaults overridden by `values`, then cross-field checks (α + β = 1, custom table).
CoverageParams parseCoverageParams(const ParamSet& values);
// Cross-field and range checks for a struct filled in code; throws InvalidParameter.
void validateCoverageParams(const CoverageParams& p);

}  // namespace rover::coverage
