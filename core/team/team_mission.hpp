#pragma once
// The team mission of paper 001 (SPEC §3) and the hybrid mission of SPEC §4, end to end: the team
// route over the PDM (route_search), one task per rover (formation slots at each target, plus the
// myopic coverage moves inside each footprint for the hybrid), prioritised planning and simulation
// (coordination), and the metrics of SPEC §3.5. Pure: the caller hands in the DEM and the PDM.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/team/coordination.hpp"
#include "core/team/route_search.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

enum class RouteMethod { LhcGwConv, Lhc, Lawnmower };
const char* routeMethodName(RouteMethod m);

struct TeamMissionParams {
  RouteMethod routeMethod = RouteMethod::LhcGwConv;  // [route]
  RouteParams route;  // targets [targets], warming levels [warming_levels], tie-break [tie_break]
  double footprint = 5.0;        // m, team footprint = search cell, SPEC §3       [footprint_m]
  double sensingDiameter = 1.0;  // m, each rover's sensed disc, SPEC §3       [sensing_diameter_m]
  terrain::TraversabilityParams traversability;  // [high_risk_deg, impassable_deg]
  CoordinationParams coordination;
  // rad; samples with |roll| or |pitch| above it are exceedances (paper 001 §4.3: 15°). Kept apart
  // from the planning limit (coordination.rrt.attitudeLimit) so a margin can be planned in.
  double exceedanceLimit = kDefaultAttitudeLimit;  //                            [exceedance_limit]
  std::uint64_t seed = 1;  // RRT*, slip and the hybrid's coverage                        [seed]
  // Hybrid only (SPEC §4): the footprint is covered on a grid of this cell (the sensing
  // diameter by default) up to this fraction of its free cells, each rover in its own Voronoi
  // region by default so team mates do not cross.
  double hybridCell = 1.0;        // m                                             [hybrid_cell_m]
  double hybridCoverage = 1.0;    // fraction                                    [hybrid_coverage]
  bool hybridVoronoi = true;      //                                             [hybrid_voronoi]

  void validate() const;
};

// Where each rover stands inside the footprint, as offsets from its centre (ours: the paper says
// the rovers spread across the footprint). The points of a ⌈√n⌉ × ⌈√n⌉ lattice of spacing
// footprint / ⌈√n⌉, taken in farthest-point order from the centre: for five rovers, the centre
// and the four corners 1.67 m out.
std::vector<Eigen::Vector2d> formationSlots(int rovers, double footprint);

// The search cell the team starts in: the one holding the centroid of the rovers' starts.
CellIndex teamStartCell(const SearchGrid& grid, const std::vector<Pose>& starts);

Route computeRoute(const SearchGrid& grid, CellIndex start, RouteMethod method,
                   const RouteParams& params);

// Legs for the team search: at every target, the target centre plus the rover's slot, moved to
// the nearest valid point (RRT* validity, at least the safety distance from the team mates'
// goals) within half a footprint when it is not; a target with no such point gives that rover no
// leg there.
// `reachable` (non-null): goals only on cells marked 1 (TraversalLattice::reachable).
std::vector<RoverTask> teamSearchTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                       const std::vector<Pose>& starts, const Route& route,
                                       const TeamMissionParams& params,
                                       const Raster<std::uint8_t>* reachable = nullptr);

// Legs for the hybrid mission: at every target, the slot leg above and then the rover's moves of
// a myopic coverage run (Laîné & Yoshida / Santra et al., SPEC §1, frontier mode, heights for β)
// over the footprint from the slots, as fixed points.
std::vector<RoverTask> hybridTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   const std::vector<Pose>& starts, const Route& route,
                                   const TeamMissionParams& params, const CancelToken* cancel,
                                   const Raster<std::uint8_t>* reachable = nullptr);

// The ground the team cannot reach from its starts (TraversalLattice::reachable), known before
// the route is chosen: map cells with data off the team's reach, and search cells that are
// passable by their terrain classes but not by what the team can reach of them.
struct ReachabilityReport {
  std::int64_t unreachableMapCells = 0;
  double unreachableAreaM2 = 0;
  double unreachableMass = 0;        // PDM mass on those cells (of 1)
  int unreachableSearchCells = 0;
  double unreachableSearchMass = 0;  // original mass of those search cells
};

// SPEC §3.5.
struct TeamMetrics {
  std::vector<double> trajectoryM;  // per rover, m over the ground
  double meanTrajectoryM = 0;
  double missionTimeS = 0;          // until the last rover stops
  std::size_t samples = 0;          // 10 Hz samples, all rovers
  std::size_t exceedances = 0;      // samples with |roll| or |pitch| > the attitude limit
  double exceedanceFraction = 0;
  double maxRollDeg = 0, maxPitchDeg = 0;
  int collisions = 0;               // episodes closer than the safety distance, any pair
  double minSeparationM = 0;
  double accumulatedProbability = 0;  // PDM mass inside the union of the sensed discs
  double singleRoverProbability = 0;  // the same for rover 0 alone
  double routeScore = 0;              // the route's own mass (search cells visited)
  int targets = 0;                    // route targets
  int targetsReached = 0;             // rover legs to a target slot that got there
  int targetsSkipped = 0;             // ... given up by wait-then-skip or off passable ground
  int targetsShort = 0;               // ... that ended away from the goal (no path)
  int targetsNoSlot = 0;              // (rover, target) pairs without valid ground for the slot
  int replans = 0, waits = 0, rrtCalls = 0;
};

// Accumulated probability vs distance (SPEC §3.5): PDM mass inside the union of the rovers'
// sensed discs (diameter `sensingDiameter`, map cells whose centre is inside), sampled every
// `every` samples. For the team, x is the mean distance per rover; `single` is rover 0 alone.
struct ProbabilityCurves {
  std::vector<std::pair<double, double>> team, single;
};
ProbabilityCurves accumulatedProbability(const Raster<float>& pdm,
                                         const std::vector<Trajectory>& trajectories,
                                         double sensingDiameter, std::size_t every = 50);

TeamMetrics teamMetrics(const CoordinationResult& plan, const ProbabilityCurves& curves,
                        const Route& route, double attitudeLimit, double safetyDistance);

// Everything a run produces.
struct TeamMissionResult {
  SearchGrid grid;  // Timed: unreachable ground counts as impassable; Paper: the terrain's own
  ReachabilityReport reachability;
  std::vector<std::pair<int, int>> noSlot;  // (rover, target) given no leg: no valid slot
  Route route;
  std::vector<Eigen::Vector2d> slots;
  CoordinationResult plan;
  ProbabilityCurves curves;
  std::vector<std::pair<double, double>> routeCurve;  // accumulatedAlongRoute
  TeamMetrics metrics;
};

// What a user must be told before trusting the plan (empty: completed cleanly): short, skipped or
// slot-less legs, unreachable ground, collisions, attitude exceedances — one line each with the
// count. The server turns a non-empty list into "completed with warnings".
std::vector<std::string> missionWarnings(const TeamMissionResult& r);

// Told the route as soon as it is chosen, then everything coordination reports.
class TeamObserver : public CoordinationObserver {
 public:
  virtual void routeChosen(const SearchGrid& grid, const Route& route) {
    (void)grid;
    (void)route;
  }
};

// `pdm`: masses on the DEM's grid (empty: every cell with data equally likely). `hybrid` selects
// SPEC §4's mission. Throws rover::Error for bad parameters or inputs (field named).
TeamMissionResult runTeamMission(const terrain::Dem& dem, const Raster<float>& pdm,
                                 const std::vector<Pose>& starts, const TeamMissionParams& params,
                                 bool hybrid, TeamObserver* observer = nullptr,
                                 const CancelToken* cancel = nullptr);

// Starts for `n` rovers in formation around `centre` (the slots, each moved to the nearest valid
// point as for a target, up to a footprint away), heading east. Throws InvalidInput "rovers"
// when there is no room.
std::vector<Pose> formationStarts(const terrain::Dem& dem, const TeamMissionParams& params,
                                  const Eigen::Vector2d& centre, int n);

// The uniform PDM used when none is given: equal mass on every cell with data, summing to 1.
Raster<float> uniformPdm(const terrain::Dem& dem);

}  // namespace rover::team
