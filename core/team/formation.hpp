#pragma once
// Where the rovers stand: the formation slots inside the team footprint, the nearest ground a
// rover may stop on near a wanted point, and formation starts around a centre (SPEC §3.2: "the
// rovers spread across the 5 m footprint").
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/team/mission_params.hpp"
#include "core/team/terrain_rrt.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

// Where each rover stands inside the footprint, as offsets from its centre (ours: the paper says
// the rovers spread across the footprint). The points of a ⌈√n⌉ × ⌈√n⌉ lattice of spacing
// footprint / ⌈√n⌉, taken in farthest-point order from the centre: for five rovers, the centre
// and the four corners 1.67 m out.
std::vector<Eigen::Vector2d> formationSlots(int rovers, double footprint);

// Where each rover starts, as offsets from the formation's centre (issue 25): the formation
// slots, spread (the whole lattice scaled up) until every two are at least startSpacing(safety)
// apart. Every rover can leave by the rule of planning::departureOrder (departure.hpp, the one
// the mission check and the coordinator apply): on open ground the outer rovers leave first, each
// inner one once the rovers round it have left. The spacing leaves each rover kStartLane more
// than twice the safety distance from its neighbours (lanes between their safety discs too
// narrow to count as a way out, so a lattice leaves from the outside in), room for the simulated
// rover's deviation from its path as the first rovers drive off past the ones still standing.
// Five rovers in a 5 m footprint (2.36 m apart) are unchanged; 20 rovers go from a 1 m to a
// 2.25 m lattice.
inline constexpr double kStartLane = 0.25;  // m, for the simulated rover's deviation from its path
inline double startSpacing(double safety) { return 2 * safety + kStartLane; }
std::vector<Eigen::Vector2d> startSlots(int rovers, double footprint, double safety);

// How far apart team mates' goals at one target are: the safety distance once each rover has
// stopped anywhere in its acceptance circle (two rovers on goals exactly the safety distance apart
// can end closer, and when the first one parks there for good the second leg can never end:
// measured on the default map, 5 rovers, 31 of 60 skipped legs in 13 missions were such pairs).
inline double goalSpacing(const CoordinationParams& c) {
  return c.safetyDistance + 2 * c.controller.acceptanceRadius;
}
// Where each rover stops round a target (issue 25): the formation slots, spread (the lattice
// scaled up, as for the starts) until every two are `spacing` apart. Five rovers in a 5 m footprint
// (2.36 m apart) are unchanged; 40 rovers would otherwise stand 0.71 m apart, closer than any two
// goals may be, and most of their slots had no ground.
std::vector<Eigen::Vector2d> goalSlots(int rovers, double footprint, double spacing);

// ours (issue 25, orienteering route only): the angle (radians, counter-clockwise) to turn the
// goal slots of a `rovers`-rover formation by at a target reached on a leg of `heading` (radians,
// counter-clockwise from east), so that every rover drives its own lane along the leg. Paper
// 001's slots are a ⌈√n⌉ = m lattice laid square to the map: on a leg along a lattice axis or
// diagonal its points share lanes (five rovers sweep three 1 m lanes, a 3 m strip of the 5 m
// footprint). Turned by atan(1/m) against the leg, lattice point (i, j) lies i + m·j lattice
// steps / √(m² + 1) to the side of the leg, distinct for every point (the rotated-grid trick):
// five rovers sweep five lanes 1.05 m apart, a 5.3 m strip. The lattice is square, so turning by
// a quarter turn more gives the same lanes; of h ± atan(1/m) the result is the one within 45° of
// 22.5° (a leg east and a leg north-east then differ by 8°, so the rovers barely move round the
// centre between them). 0 for one rover. Measured (`sweep --preset swinton --runs 20`, same 20
// PDMs, orienteering against LHC_GW_CONV): p at 300 m per rover x1.17 -> x1.23 paired on the
// synthetic Mars site (19/20 PDMs better), x1.24 on HiRISE; the team's swept strip, not the route,
// was what held it back.
double laneTurn(int rovers, double heading);
// `slots` turned by `angle` radians counter-clockwise about the centre (distances kept).
std::vector<Eigen::Vector2d> turnedSlots(const std::vector<Eigen::Vector2d>& slots, double angle);

// The heading rule of the turned slots along a route (one team): each target's slots turned by
// laneTurn to the heading of the step from the team's previous target, from the starts' centroid
// for its first one; a repeated target keeps the last heading. The task builder's goals and
// `bench routes`' swept measure both use it, so the bench models the lanes the missions drive.
class LaneHeading {
 public:
  explicit LaneHeading(const Eigen::Vector2d& from) : last_(from) {}
  // `slots` (the team's formation, one per rover) as they stand round `centre`, the next target.
  std::vector<Eigen::Vector2d> slotsAt(const std::vector<Eigen::Vector2d>& slots, const Eigen::Vector2d& centre);

 private:
  Eigen::Vector2d last_;
  double heading_ = 0;
};

// The rover's validity rules on the whole map (the RRT*'s attitude limit and edge resolution).
TerrainEdgeModel wholeMapModel(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                               const RrtParams& rrt);

// Where a rover stops at a goal: anywhere in its acceptance circle, and a little more for the
// last approach.
inline double stopCircleRadius(const ControllerParams& c) { return c.acceptanceRadius + 0.05; }
// `p` and eight points on the circle of `radius` round it are turnValid (radius 0: `p` alone).
bool turnableAround(const TerrainEdgeModel& model, const Eigen::Vector2d& p, double radius);

// The nearest point to `want` (rings of a quarter metre, up to `reach`) that RRT* accepts as a
// goal (turnValid), keeps `safety` from every point of `taken` and, with `reachable`, lies on a
// cell marked 1 there; with `stopRadius` > 0, it is turnableAround that radius, so wherever a
// rover stops in its acceptance circle it can most likely turn there (ours: on the HiRISE site
// rovers stopped 0.2 m from a valid goal on a 15° spot, and every later leg tilted while
// turning); with `accept`, a point it accepts (checked last: it may be dear). nullopt when there
// is none.
std::optional<Eigen::Vector2d> nearestValid(const TerrainEdgeModel& model, Eigen::Vector2d want,
                                            double reach, double safety,
                                            const std::vector<Eigen::Vector2d>& taken,
                                            const Raster<std::uint8_t>* reachable = nullptr,
                                            double stopRadius = 0,
                                            const std::function<bool(const Eigen::Vector2d&)>& accept = {});

// Starts for `n` rovers in formation around `centre` (startSlots, each moved to the nearest valid
// point as for a target, up to a footprint or a slot spacing away, keeping startSpacing from the
// starts placed before, and never in a pocket a rover alone cannot get out of over passable
// ground: planning::departureOrder for that one start, the mission check's test), and, after the
// first start, only where the first one's ground on the traversal lattice is (the rover's own
// validity rules, TraversalLattice::startsWithin, on a window of the map round the formation:
// no start on ground cut off from its team mates'), heading east. The lattice itself leaves by the same rule from the outside in
// (startSlots). Throws
// InvalidInput "rovers" when there is no room. The first form computes the traversability
// classes itself.
std::vector<Pose> formationStarts(const terrain::Dem& dem, const TeamMissionParams& params,
                                  const Eigen::Vector2d& centre, int n);
std::vector<Pose> formationStarts(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                  const TeamMissionParams& params, const Eigen::Vector2d& centre,
                                  int n);

}  // namespace rover::team
