#include "core/team/orienteering_route.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <vector>

namespace rover::team {

namespace {

// The passable cells 8-connected to `start` (the start itself included even when impassable: the
// team may be set down there and drives out).
std::vector<std::uint8_t> reachableFrom(const SearchGrid& grid, CellIndex start) {
  const GridGeometry& g = grid.geometry();
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(g.cellCount()), 0);
  std::vector<CellIndex> stack{start};
  seen[static_cast<std::size_t>(g.index(start))] = 1;
  while (!stack.empty()) {
    const CellIndex c = stack.back();
    stack.pop_back();
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const CellIndex n{c.row + dr, c.col + dc};
        if ((dr == 0 && dc == 0) || !g.contains(n) || !grid.passable(n)) continue;
        auto& s = seen[static_cast<std::size_t>(g.index(n))];
        if (s == 0) {
          s = 1;
          stack.push_back(n);
        }
      }
  }
  return seen;
}

// The open path being improved: node 0 is the start, the others index `centres`/`mass`.
class OpenPath {
 public:
  OpenPath(std::vector<Eigen::Vector2d> centres, std::vector<double> mass, double budget, int maxTargets,
           double greed)
      : centres_(std::move(centres)), mass_(std::move(mass)), budget_(budget), maxTargets_(maxTargets), greed_(greed),
        used_(centres_.size(), 0) {
    path_.push_back(0);
    used_[0] = 1;
  }

  const std::vector<int>& nodes() const { return path_; }
  // Keeps the path as it is and lets later moves only extend it past its end, within a new budget
  // and target count and with a new insertion power: phase 2 of the two-phase route.
  void extend(double budget, int maxTargets, double greed) {
    frozen_ = path_.size();
    budget_ = budget;
    maxTargets_ = maxTargets;
    greed_ = greed;
  }
  // The mass of the nodes reached within `metres` along the path (start included).
  double collectedBy(double metres) const {
    double m = mass_[static_cast<std::size_t>(path_[0])], d = 0;
    for (std::size_t i = 1; i < path_.size(); ++i) {
      d += dist(path_[i - 1], path_[i]);
      if (d > metres) break;
      m += mass_[static_cast<std::size_t>(path_[i])];
    }
    return m;
  }
  double collected() const {
    double m = 0;
    for (int n : path_) m += mass_[static_cast<std::size_t>(n)];
    return m;
  }

  // Inserts unvisited nodes one at a time, each the one with the most mass per added metre
  // (ties: the lower node, then the earlier position) that keeps the path within the budget.
  bool insertGreedily() {
    bool any = false;
    while (static_cast<int>(path_.size()) - 1 < maxTargets_) {
      int bestNode = -1;
      std::size_t bestAt = 0;
      double bestRatio = -1, bestDelta = 0;
      for (int n = 1; n < static_cast<int>(centres_.size()); ++n) {
        if (used_[static_cast<std::size_t>(n)]) continue;
        for (std::size_t at = frozen_; at <= path_.size(); ++at) {
          const double delta = addedLength(n, at);
          if (length_ + delta > budget_) continue;
          // A metre of slack keeps neighbours of the path from dividing by ~0.
          const double ratio = std::pow(mass_[static_cast<std::size_t>(n)], greed_) / (delta + 1.0);
          if (ratio > bestRatio) {
            bestRatio = ratio;
            bestNode = n;
            bestAt = at;
            bestDelta = delta;
          }
        }
      }
      if (bestNode < 0) break;
      path_.insert(path_.begin() + static_cast<std::ptrdiff_t>(bestAt), bestNode);
      used_[static_cast<std::size_t>(bestNode)] = 1;
      length_ += bestDelta;
      any = true;
    }
    return any;
  }

  // 2-opt on the open path (node 0 fixed): reverses a stretch when that shortens it.
  bool shorten() {
    bool any = false;
    for (bool improved = true; improved;) {
      improved = false;
      for (std::size_t i = frozen_; i + 1 < path_.size(); ++i)
        for (std::size_t j = i + 1; j < path_.size(); ++j) {
          // Edges (i−1, i) and (j, j+1) become (i−1, j) and (i, j+1); no j+1 past the end.
          const double before = dist(path_[i - 1], path_[i]) + (j + 1 < path_.size() ? dist(path_[j], path_[j + 1]) : 0);
          const double after = dist(path_[i - 1], path_[j]) + (j + 1 < path_.size() ? dist(path_[i], path_[j + 1]) : 0);
          if (after < before - 1e-9) {
            std::reverse(path_.begin() + static_cast<std::ptrdiff_t>(i), path_.begin() + static_cast<std::ptrdiff_t>(j) + 1);
            length_ += after - before;
            improved = any = true;
          }
        }
    }
    return any;
  }

  // Replaces one visited node by a heavier unvisited one, inserted at the first place that keeps
  // the path within the budget; the first such swap in path order is made. Each swap raises the
  // collected mass, so swaps cannot cycle.
  bool swapForHeavier() {
    for (std::size_t i = frozen_; i < path_.size(); ++i) {
      const int out = path_[i];
      const double removed = removedLength(i);
      std::vector<int> without = path_;
      without.erase(without.begin() + static_cast<std::ptrdiff_t>(i));
      // Nodes are in descending mass: only those before `out` can be heavier.
      for (int n = 1; n < out; ++n) {
        if (used_[static_cast<std::size_t>(n)] || mass_[static_cast<std::size_t>(n)] <= mass_[static_cast<std::size_t>(out)])
          continue;
        for (std::size_t at = frozen_; at <= without.size(); ++at) {
          const double delta = addedLengthIn(without, n, at);
          if (length_ - removed + delta > budget_) continue;
          without.insert(without.begin() + static_cast<std::ptrdiff_t>(at), n);
          path_ = std::move(without);
          used_[static_cast<std::size_t>(out)] = 0;
          used_[static_cast<std::size_t>(n)] = 1;
          length_ += delta - removed;
          return true;
        }
      }
    }
    return false;
  }

 private:
  double dist(int a, int b) const {
    return (centres_[static_cast<std::size_t>(a)] - centres_[static_cast<std::size_t>(b)]).norm();
  }
  double addedLengthIn(const std::vector<int>& p, int n, std::size_t at) const {
    const int prev = p[at - 1];
    if (at == p.size()) return dist(prev, n);
    return dist(prev, n) + dist(n, p[at]) - dist(prev, p[at]);
  }
  double addedLength(int n, std::size_t at) const { return addedLengthIn(path_, n, at); }
  double removedLength(std::size_t i) const {
    const int prev = path_[i - 1], node = path_[i];
    if (i + 1 == path_.size()) return dist(prev, node);
    return dist(prev, node) + dist(node, path_[i + 1]) - dist(prev, path_[i + 1]);
  }

  std::vector<Eigen::Vector2d> centres_;
  std::vector<double> mass_;
  double budget_;
  int maxTargets_;
  double greed_;  // insertion ranks by mass^greed per added metre
  std::vector<std::uint8_t> used_;
  std::vector<int> path_;
  std::size_t frozen_ = 1;  // path_[0, frozen_) is fixed: the start, then phase 1 once extended
  double length_ = 0;
};

constexpr double kGreedPowers[] = {1.0, 2.0, 4.0};

}  // namespace

Route orienteeringRoute(const SearchGrid& grid, CellIndex start, const RouteParams& params) {
  validateRouteParams(params);
  Route probe = scoredRoute(grid, start, {});  // checks the start
  const GridGeometry& g = grid.geometry();
  const std::vector<std::uint8_t> reach = reachableFrom(grid, start);
  std::vector<CellIndex> cells;
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      const CellIndex cell{r, c};
      if (reach[static_cast<std::size_t>(g.index(cell))] && grid.passable(cell) && !(cell == start) && grid.mass(r, c) > 0)
        cells.push_back(cell);
    }
  if (cells.empty()) return lawnmower(grid, start, params.targets);
  // The heaviest candidates, ties row-major (stable on the row-major list).
  std::stable_sort(cells.begin(), cells.end(),
                   [&](CellIndex a, CellIndex b) { return grid.mass(a.row, a.col) > grid.mass(b.row, b.col); });
  if (cells.size() > static_cast<std::size_t>(kOrienteeringCandidates)) cells.resize(kOrienteeringCandidates);
  std::vector<Eigen::Vector2d> centres{probe.startCentre};
  std::vector<double> mass{0.0};
  for (const CellIndex& c : cells) {
    centres.push_back(grid.centre(c));
    mass.push_back(grid.mass(c.row, c.col));
  }
  // The separated masses: candidate cells at least as heavy as each of their 8 neighbours and
  // at least 1 % of the heaviest (flat crumbs are not masses). A path visits one when it has a
  // target within 2 cells of it (Chebyshev).
  std::vector<CellIndex> peaks;
  const double heaviest = grid.mass(cells.front().row, cells.front().col);
  for (const CellIndex& c : cells) {
    const double m = grid.mass(c.row, c.col);
    if (m < 0.01 * heaviest) continue;
    bool peak = true;
    for (int dr = -1; dr <= 1 && peak; ++dr)
      for (int dc = -1; dc <= 1; ++dc)
        if (g.contains(CellIndex{c.row + dr, c.col + dc}) && grid.mass(c.row + dr, c.col + dc) > m) {
          peak = false;
          break;
        }
    if (peak) peaks.push_back(c);
  }
  auto visitedPeaks = [&](const OpenPath& path) {
    std::vector<std::uint8_t> seen(peaks.size(), 0);
    for (std::size_t i = 1; i < path.nodes().size(); ++i) {
      const CellIndex& c = cells[static_cast<std::size_t>(path.nodes()[i] - 1)];
      for (std::size_t k = 0; k < peaks.size(); ++k)
        if (std::max(std::abs(c.row - peaks[k].row), std::abs(c.col - peaks[k].col)) <= 2) seen[k] = 1;
    }
    return seen;
  };
  // Greedy insertion ranks by mass^greed per added metre: 1 favours cheap cells near the path,
  // larger powers the heavy cores farther away. Each is improved by local search (shorten,
  // fill the freed length, trade light cells for heavy ones; each round improves the path or
  // ends the search, the bound only catches a cycle of equal moves); the most mass wins, ties
  // to the lower power.
  auto improve = [&](OpenPath& path) {
    path.insertGreedily();
    for (int round = 0; round < 4 * params.targets; ++round) {
      const bool shorter = path.shorten();
      const bool filled = path.insertGreedily();
      const bool swapped = path.swapForHeavier();
      if (!shorter && !filled && !swapped) break;
    }
  };
  auto keepBest = [](std::optional<OpenPath>& best, OpenPath&& path) {
    if (!best || path.collected() > best->collected()) best = std::move(path);
  };
  const double budget = params.targets * grid.footprint;
  std::optional<OpenPath> best;
  for (double greed : kGreedPowers) {
    OpenPath path(centres, mass, budget, params.targets, greed);
    improve(path);
    keepBest(best, std::move(path));
  }
  // Two phases when the budget reaches past the horizon: the most mass within the horizon first,
  // then on from its end with the rest of the budget and targets (whole-PDM orienteering again, so
  // the remaining separated masses are still sought). The route best at its end is often not the
  // best by the horizon, where the measure is read. Kept only when it has strictly more mass by
  // the horizon than the one-phase route and visits every separated mass that route visits (the
  // horizon must not cost a Gaussian the whole-PDM route reaches: issue 25's caldera case).
  if (budget > kOrienteeringHorizonM) {
    std::optional<OpenPath> early;
    for (double greed : kGreedPowers) {
      // The horizon's share of the targets, so phase 2 has targets left to reach the other masses.
      OpenPath path(centres, mass, kOrienteeringHorizonM, static_cast<int>(kOrienteeringHorizonM / grid.footprint), greed);
      improve(path);
      keepBest(early, std::move(path));
    }
    std::optional<OpenPath> extended;
    for (double greed : kGreedPowers) {
      OpenPath path = *early;
      path.extend(budget, params.targets, greed);
      improve(path);
      keepBest(extended, std::move(path));
    }
    const std::vector<std::uint8_t> wholeVisits = visitedPeaks(*best), twoPhaseVisits = visitedPeaks(*extended);
    bool keepsMasses = true;
    for (std::size_t k = 0; k < peaks.size(); ++k)
      if (wholeVisits[k] && !twoPhaseVisits[k]) keepsMasses = false;
    if (keepsMasses && extended->collectedBy(kOrienteeringHorizonM) > best->collectedBy(kOrienteeringHorizonM))
      best = std::move(extended);
  }
  std::vector<CellIndex> route;
  for (std::size_t i = 1; i < best->nodes().size(); ++i) route.push_back(cells[static_cast<std::size_t>(best->nodes()[i] - 1)]);
  return scoredRoute(grid, start, std::move(route));
}

}  // namespace rover::team
