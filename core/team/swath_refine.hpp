#pragma once
// What the team actually sees along a route, and a local search on it (issue 25). A route's own
// score counts a target cell's whole mass, but five rovers with 1 m sensed discs in the formation
// of formationSlots (the centre and four corners 1.67 m out) see only a swath along the legs:
// 3 m wide when they drive along a row, column or diagonal (rovers hide behind each other), about
// 4.5 m on legs of slope 1:2, and only five 1 m discs where they stand. SPEC §3.5's accumulated
// probability is that swath's mass against the distance per rover, so the orienteering route
// (greedy on whole cells) is refined here on the swath itself: the mass under the rovers' discs,
// driving straight between target centres in formation, by a horizon distance.
//
// Choices made here:
// - The search grid holds only each cell's mass, so the density is taken as uniform inside a
//   cell, on sub-cells of footprint/10 (0.5 m for 5 m cells): a disc marks the sub-cells whose
//   centre it covers.
// - The team is the paper's five rovers (a sub-team has at most five), each sensing a 1 m disc.
// - Moves: replace a target by a passable reachable cell within two cells of it and not yet a
//   target (a knight's move turns a leg to the wide 1:2 slope), or drop it; first improvement,
//   in route order, until a pass improves nothing or the evaluation cap is spent. The cap is a count, not a clock, so the
//   same grid gives the same route on every machine.
#include <cstdint>
#include <vector>

#include "core/team/route_search.hpp"

namespace rover::team {

inline constexpr int kSwathRovers = 5;
inline constexpr double kSwathSensingDiameter = 1.0;  // m, SPEC §3
inline constexpr int kSwathSubCells = 10;             // sub-cells per search-cell side
inline constexpr int kSwathEvaluationCap = 2000;     // route evaluations per refinement
inline constexpr double kSwathHorizon = 0.9;          // of the length budget

class SwathModel {
 public:
  explicit SwathModel(const SearchGrid& grid);
  // The mass under the rovers' discs driving straight from `start` through `stops` in formation,
  // by `horizon` metres per rover (the whole route when it is shorter).
  double seen(const Eigen::Vector2d& start, const std::vector<Eigen::Vector2d>& stops, double horizon) const;
  // The same in two parts, for many routes that share their first `count` stops: keepPrefix
  // marks the start and the legs to stops[count − 1] once; seenAfter then adds the legs from there
  // through stops[count..] of each route (stops[0, count) must be the kept ones). The sum is
  // exactly seen()'s, as each leg is sampled from its own start.
  void keepPrefix(const Eigen::Vector2d& start, const std::vector<Eigen::Vector2d>& stops, std::size_t count,
                  double horizon) const;
  double seenAfter(const std::vector<Eigen::Vector2d>& stops, std::size_t count, double horizon) const;
  bool prefixReachesHorizon() const { return baseDone_; }

 private:
  void mark(const Eigen::Vector2d& p, double& mass) const;
  std::uint32_t nextGeneration() const;
  // Marks the legs from `a` (at `d` metres) through stops[from..] up to the horizon; false when
  // the horizon was reached.
  bool walk(Eigen::Vector2d& a, double& d, const std::vector<Eigen::Vector2d>& stops, std::size_t from,
            std::size_t to, double horizon, double& mass) const;
  const SearchGrid& grid_;
  double sub_;                                 // sub-cell side, m
  int rows_, cols_;                            // sub-cell grid
  std::vector<Eigen::Vector2d> slots_;
  // A sub-cell is seen when its stamp is base_ (the kept prefix) or generation_ (this route).
  mutable std::vector<std::uint32_t> stamp_;
  mutable std::uint32_t generation_ = 0, base_ = UINT32_MAX;
  mutable double baseMass_ = 0, baseDistance_ = 0;
  mutable Eigen::Vector2d baseEnd_{0, 0};
  mutable bool baseDone_ = false;  // the prefix already reached the horizon
};

// Improves `route.cells` for SwathModel::seen by `horizon` metres, keeping the route within
// `budget` metres of straight legs and its targets on cells with reach[index] = 1 (the start's
// passable region). Returns the refined cells.
std::vector<CellIndex> refineForSwath(const SearchGrid& grid, const Route& route, const std::vector<std::uint8_t>& reach,
                                      double budget, double horizon);

}  // namespace rover::team
