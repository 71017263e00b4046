#pragma once
// Which neighbour a coverage rover moves to (SPEC §1 step 2), a stage of the coverage engine
// (core/coverage/coverage_planner.cpp): the cheapest move of paper 000 eq. 3 over paper 002's
// cost tables, obstacle circumnavigation (paper 002 §2.2) and our frontier mode. It reads the
// rover's own map and the team's occupancy; it never moves anyone.
#include <array>
#include <cstdint>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_rover.hpp"
#include "core/coverage/team_occupancy.hpp"
#include "core/coverage/world.hpp"

namespace rover::coverage {

class MovePolicy {
 public:
  MovePolicy(const World& world, const CoverageParams& params, const TeamOccupancy& team);

  // The next cell for `r`, or -1 when it has no legal move this step. In frontier mode a rover
  // with nothing reachable left unexplored is marked done (NothingLeft).
  // Inline: the engine asks every move, and most moves go straight to costStep.
  int choose(CoverageRover& r) {
    if (p_.frontier && !hasUnvisitedNeighbour(r)) {
      r.circling = false;
      return frontierStep(r);
    }
    r.plan.clear();
    if (r.circling) {
      int next = contourStep(r, false);
      if (next >= 0) return next;
      r.circling = false;
    }
    return costStep(r);
  }
  // After a move made while circling: gives up or regains the line. Returns the heading the
  // rover had when it turned back onto its line (a spot turn the caller books), else -1.
  int afterContourMove(CoverageRover& r);
  // No neighbour the rover's map lets it enter, team mates aside.
  bool walledIn(const CoverageRover& r) const;

 private:
  const KnowledgeMap& mapOf(const CoverageRover& r) const { return team_.map(r.mapId); }
  // In the grid (the caller's neighbour), in the rover's region, not a known obstacle, and not
  // held by another rover.
  bool enterable(const CoverageRover& r, int i) const;
  bool hasUnvisitedNeighbour(const CoverageRover& r) const;
  int costStep(CoverageRover& r);
  int contourStep(CoverageRover& r, bool first) const;
  bool touchesKnownObstacle(const KnowledgeMap& m, int cell) const;
  bool worthCircling(const CoverageRover& r) const;
  int frontierStep(CoverageRover& r);
  int bfsToFrontier(CoverageRover& r, bool avoidRovers);

  const World& world_;
  const GridGeometry& g_;
  const CoverageParams& p_;
  const TeamOccupancy& team_;
  // mc_static of every relative move from every heading (paper 002 eq. 1), indexed
  // [heading][rel]: the table's relative + absolute cost, added once instead of per move.
  std::array<std::array<double, 8>, 8> staticCost_{};
  // Paper 000 eq. 3's height term only where it can be non-zero (β > 0 on a world with heights).
  bool heightTerm_ = false;
  // Flat-index offset of the neighbour `rel` steps left of each heading, for cells off the
  // border, and which cells are on it (a lookup instead of GridGeometry::cell's division).
  std::array<std::array<int, 8>, 8> offset_{};
  std::vector<std::uint8_t> onBorder_;
  // Breadth-first search scratch, reused between searches (a stamp instead of clearing).
  std::vector<int> bfsParent_;
  std::vector<std::uint32_t> bfsSeen_;
  std::uint32_t bfsStamp_ = 0;
  std::vector<int> bfsQueue_;
};

}  // namespace rover::coverage
