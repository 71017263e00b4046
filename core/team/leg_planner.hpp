#pragma once
// The leg planner stage (SPEC §3.2): one planning problem of a rover's leg — from where it stands
// to its goal, out of the keep-out zones — answered with a path. The coordinator asks it and
// never looks at the terrain itself, so it can be driven by a fake planner in tests.
// Two planners:
// - BoxedRrtPlanner: paper 001 §3.6 as SPEC §3.2 reads it, RRT* (1250 vertices, 1 m range, eq. 9)
//   in the box of start and goal grown by the clearance.
// - GuidedRrtPlanner (ours, issue 10): a guide path on the traversal lattice (A*, eq. 9 per move),
//   RRT* in a corridor around it, and the guide itself when RRT* ends short — valid by
//   construction, so a leg to a reachable goal reaches it. Without a guide (the goal's cell cannot
//   be reached) the boxed RRT* still gets its chance.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/grid/raster.hpp"
#include "core/team/terrain_rrt.hpp"
#include "core/team/traversal_lattice.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

class LegPlanner {
 public:
  virtual ~LegPlanner() = default;
  // A path from `from` (facing `heading`) to `goal`, first waypoint `from`, staying out of
  // `keepOut`. Deterministic for a seed. Cancelled when `cancel` is set.
  virtual PathResult plan(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal,
                          std::uint64_t seed, const std::vector<KeepOutZone>& keepOut,
                          const CancelToken* cancel) const = 0;
  // A straight move the rover may drive: the fixed points of a hybrid leg are checked with it.
  virtual bool edgeValid(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const = 0;
  // A point where the rover may stop and turn in place (a parking spot).
  virtual bool canStop(const Eigen::Vector2d& p) const = 0;
  // A point no simulated sample may reach: a cell of an operator's keep-out zone.
  virtual bool forbidden(const Eigen::Vector2d& p) const {
    (void)p;
    return false;
  }
};

// The validity checks both terrain planners share: the rover's rules on the whole map.
class TerrainLegPlanner : public LegPlanner {
 public:
  // Holds references: the rasters must outlive it.
  TerrainLegPlanner(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                    const RrtParams& rrt, const TerrainCostWeights& weights);
  bool edgeValid(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const override {
    return wholeMap_.edgeValid(a, b);
  }
  bool canStop(const Eigen::Vector2d& p) const override { return wholeMap_.turnValid(p); }
  bool forbidden(const Eigen::Vector2d& p) const override { return wholeMap_.inZone(p); }

 protected:
  // planPath in the start/goal box.
  PathResult boxed(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal,
                   std::uint64_t seed, const std::vector<KeepOutZone>& keepOut,
                   const CancelToken* cancel, const Corridor* corridor = nullptr) const;
  const terrain::Dem& dem_;
  const Raster<std::uint8_t>& classes_;
  RrtParams rrt_;
  TerrainCostWeights weights_;
  TerrainEdgeModel wholeMap_;
};

class BoxedRrtPlanner final : public TerrainLegPlanner {
 public:
  using TerrainLegPlanner::TerrainLegPlanner;
  PathResult plan(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal,
                  std::uint64_t seed, const std::vector<KeepOutZone>& keepOut,
                  const CancelToken* cancel) const override {
    return boxed(from, heading, goal, seed, keepOut, cancel);
  }
};

class GuidedRrtPlanner final : public TerrainLegPlanner {
 public:
  // `lattice` must be built on the same DEM and classes with the RRT*'s attitude limit.
  GuidedRrtPlanner(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                   const TraversalLattice& lattice, const RrtParams& rrt,
                   const TerrainCostWeights& weights, double corridorRadius);
  PathResult plan(const Eigen::Vector2d& from, double heading, const Eigen::Vector2d& goal,
                  std::uint64_t seed, const std::vector<KeepOutZone>& keepOut,
                  const CancelToken* cancel) const override;

 private:
  const TraversalLattice& lattice_;
  double corridorRadius_;
};

}  // namespace rover::team
