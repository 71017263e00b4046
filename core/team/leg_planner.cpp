#include "core/team/leg_planner.hpp"

#include <algorithm>
#include <cmath>

namespace rover::team {

TerrainLegPlanner::TerrainLegPlanner(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                     const RrtParams& rrt, const TerrainCostWeights& weights)
    : dem_(dem),
      classes_(classes),
      rrt_(rrt),
      weights_(weights),
      wholeMap_(dem, classes, mapBounds(dem.geometry()), rrt.attitudeLimit,
                edgeResolutionOn(dem.geometry(), rrt)) {}

PathResult TerrainLegPlanner::boxed(const Eigen::Vector2d& from, double heading,
                                    const Eigen::Vector2d& goal, std::uint64_t seed,
                                    const std::vector<KeepOutZone>& keepOut,
                                    const CancelToken* cancel, const Corridor* corridor) const {
  RrtParams rrt = rrt_;
  rrt.seed = seed;
  // Only the zones that reach into the search bounds (the tree never leaves them, so the others
  // change nothing): a timed leg gets a zone round every standing team mate's start
  // (ConflictPolicy::standingKeepOut), up to 63, and RRT* tests every zone at every point it checks.
  const SearchBounds box = corridor ? corridor->bounds : searchBounds(dem_.geometry(), from, goal, rrt.clearance);
  std::vector<KeepOutZone> near;
  for (const KeepOutZone& z : keepOut) {
    const Eigen::Vector2d q = z.centre.cwiseMax(box.min).cwiseMin(box.max);
    // Kept: a zone the planner refuses (not finite, negative), and one reaching the box.
    if (!z.centre.allFinite() || !std::isfinite(z.radius) || z.radius < 0 || (q - z.centre).norm() <= z.radius)
      near.push_back(z);
  }
  return planPath(dem_, classes_, from, heading, goal, rrt, weights_, cancel, near, corridor);
}

GuidedRrtPlanner::GuidedRrtPlanner(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   const TraversalLattice& lattice, const RrtParams& rrt,
                                   const TerrainCostWeights& weights, double corridorRadius)
    : TerrainLegPlanner(dem, classes, rrt, weights), lattice_(lattice), corridorRadius_(corridorRadius) {}

PathResult GuidedRrtPlanner::plan(const Eigen::Vector2d& from, double heading,
                                  const Eigen::Vector2d& goal, std::uint64_t seed,
                                  const std::vector<KeepOutZone>& keepOut,
                                  const CancelToken* cancel) const {
  bool proven = false;
  auto guide = lattice_.guidePath(from, goal, keepOut, &proven);
  if (!guide) {
    PathResult r = boxed(from, heading, goal, seed, keepOut, cancel);
    r.goalCutOff = proven;
    return r;
  }
  // The corridor holds the paper's box too: never less room than the boxed planner, and on a
  // straight leg the same tree density (a corridor alone packs the 1250 vertices tighter, which
  // costs rewiring time for nothing).
  const SearchBounds box = searchBounds(dem_.geometry(), from, goal, rrt_.clearance);
  const Corridor corridor = lattice_.corridor(*guide, corridorRadius_, &box);
  PathResult r = boxed(from, heading, goal, seed, keepOut, cancel, &corridor);
  if (r.status == PathStatus::Exact || r.status == PathStatus::Cancelled ||
      r.status == PathStatus::InvalidGoal)
    return r;
  PathResult g;
  g.status = PathStatus::Exact;
  g.waypoints = std::move(*guide);
  g.cost = pathCost(lattice_.model(), g.waypoints, heading, weights_, false);
  g.costWithTurns = pathCost(lattice_.model(), g.waypoints, heading, weights_, true);
  g.vertices = r.vertices;
  g.iterations = r.iterations;
  return g;
}

}  // namespace rover::team
