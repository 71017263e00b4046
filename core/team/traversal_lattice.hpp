#pragma once
// The global layer under RRT* (paper 000 fig. 2: global planning on orbital data, local planning
// in situ; ours for paper 001's team): the DEM's cell centres as an 8-connected lattice, with the
// rover's own validity rules on every node and move (TerrainEdgeModel: classes, nodata, |roll| and
// |pitch| along the move) and the eq. 9 terrain cost of each move, built once per mission.
// On it: the ground the team can reach from its starts (a flood fill, so a walled-in region is
// known before any target is chosen) and a guide path per leg (A*), around which RRT* then plans
// in a corridor instead of the start/goal box.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/grid/direction.hpp"
#include "core/grid/raster.hpp"
#include "core/planning/departure.hpp"
#include "core/team/terrain_rrt.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

class TraversalLattice {
 public:
  // Holds references: the rasters must outlive it. `threads` (0 = all cores) builds the move
  // table; the result does not depend on it.
  TraversalLattice(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                   double attitudeLimit, double edgeResolution, const TerrainCostWeights& weights,
                   double range, unsigned threads);
  TraversalLattice(terrain::Dem&&, const Raster<std::uint8_t>&, double, double,
                   const TerrainCostWeights&, double, unsigned) = delete;

  const GridGeometry& geometry() const { return classes_.geometry; }
  const TerrainEdgeModel& model() const { return model_; }

  // Cells the rovers can reach from `starts` (1 = reachable): flood fill over valid moves between
  // valid nodes (turnValid: a rover may stop and turn there). A start's own cell and the valid
  // cells within 0.5 m of it seed the fill even when the start itself is steep (RRT* escapes it
  // the same way).
  Raster<std::uint8_t> reachable(const std::vector<Eigen::Vector2d>& starts) const;
  // Whether a rover standing at `p` would reach the ground `region` marks and no other: every
  // cell its flood starts from (as in reachable) is marked there, `region` being what reachable()
  // returned (closed under the moves, which are symmetric). False off the map. A formation's
  // starts are held to the first start's ground with it (formation.hpp).
  bool startsWithin(const Raster<std::uint8_t>& region, const Eigen::Vector2d& p) const;

  // The cheapest lattice path from `start` to `goal` (A*, eq. 9 per move, see the .cpp), as
  // waypoints: `start`, cell centres, `goal`, simplified to straight valid edges no longer than
  // the range. Nodes inside a keep-out zone are blocked. nullopt when the goal's cell cannot be
  // reached (or the start's cell has no valid move); `proven` (optional) then tells whether that
  // is certain, rather than the search window growing past its bound on a huge map.
  std::optional<std::vector<Eigen::Vector2d>> guidePath(
      const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
      const std::vector<KeepOutZone>& keepOut = {}, bool* proven = nullptr) const;

  // Cells whose centre is within `radius` of a point of `path` (sampled every half cell), and
  // every cell `box` touches when given, as a corridor for planPath.
  Corridor corridor(const std::vector<Eigen::Vector2d>& path, double radius,
                    const SearchBounds* box = nullptr) const;

 private:
  const terrain::Dem& dem_;
  const Raster<std::uint8_t>& classes_;
  TerrainEdgeModel model_;
  double range_;
  double heuristicPerMetre_ = 0;
  // Memory: 9 bytes per map cell (a node flag and four 16-bit move costs), e.g. 3.2 MB for the
  // paper's 600 × 600 site, 450 MB for the server's largest map (50 M cells).
  std::vector<std::uint8_t> node_;  // 1 = turnValid at the cell centre
  // Per cell, the moves E, NE, N, NW (the other four are the neighbours' opposite moves, the
  // terms being symmetric), quantised by costStep_; kInvalid = not a valid move.
  std::vector<std::uint16_t> cost_;
  double costStep_ = 1.0;
  static constexpr std::uint16_t kInvalid = 0xFFFF;
  // The cost of the move from `cell` in direction `dir` (0..7), < 0 when invalid or off the grid.
  float moveCost(int cell, int dir) const {
    const GridGeometry& g = classes_.geometry;
    const int row = cell / g.cols, col = cell % g.cols;
    if (!g.contains(row + kDirRow[dir], col + kDirCol[dir])) return -1.0f;
    std::size_t slot;
    if (dir < 4) {
      slot = static_cast<std::size_t>(cell) * 4 + dir;
    } else {
      const int j = g.index(row + kDirRow[dir], col + kDirCol[dir]);
      slot = static_cast<std::size_t>(j) * 4 + (dir - 4);
    }
    const std::uint16_t q = cost_[slot];
    return q == kInvalid ? -1.0f : static_cast<float>(q * costStep_);
  }
  std::vector<int> seeds(const Eigen::Vector2d& p) const;
  enum class FloodStep { Skip, Push, Stop };
  template <class Step>
  bool flood(std::vector<int> stack, Step step) const;
  struct Window;
  // A* from the seeds `from` to the cell `target` inside the window (see the .cpp).
  std::optional<std::vector<Eigen::Vector2d>> search(const std::vector<int>& from,
                                                     const Eigen::Vector2d& start, int target,
                                                     const Eigen::Vector2d& goal,
                                                     const Window& w, bool& clipped) const;
  // Whether `target` can be entered from a cell of `from` at all, flooding back from it inside the
  // window: false is final when the flood was not clipped by the window's edge.
  bool connected(const std::vector<int>& from, int target, const Window& w, bool& clipped) const;
  std::vector<Eigen::Vector2d> simplify(const std::vector<Eigen::Vector2d>& chain,
                                        const Eigen::Vector2d& start,
                                        const Eigen::Vector2d& goal) const;
};

// The ground `region` marks (1 = passable; off the grid: not), for planning::departureOrder: with
// the lattice's flood from the starts, the ways out the rovers can really drive (issue 25: on
// the Kepler site, with open ground, 9 of 64 rovers in the formation's edge against the crater
// wall were planned first, while every team mate still stood between them and the floor, and
// every leg of theirs ended short). The region must outlive the result.
planning::PassableGround groundIn(const Raster<std::uint8_t>& region);
// The team's departure order (planning::departureOrder) with the ground it was taken over:
// groundIn(region) when every rover at `starts` has a way out over it, else open ground (`ground`
// an empty function: on a small map or region the way-out test's margin reaches past the ground,
// and the coordinator would refuse starts it planned before). The coordinator (coordination.cpp)
// and the task builder's goal ranks (task_builder.cpp) both take it, so they agree on the order;
// each computes it once (twice when it falls back). `ground` refers to `region`, which must
// outlive it.
struct GroundDeparture {
  planning::Departure departure;
  planning::PassableGround ground;  // empty: open ground
};
GroundDeparture departureOverGround(const std::vector<Eigen::Vector2d>& starts, double safety,
                                    const Raster<std::uint8_t>& region);

}  // namespace rover::team
