#include "core/coverage/move_policy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/grid/neighbours.hpp"

namespace rover::coverage {

MovePolicy::MovePolicy(const World& world, const CoverageParams& params, const TeamOccupancy& team)
    : world_(world), g_(world.geometry()), p_(params), team_(team) {
  const MotionCostTable table = params.table();
  for (int heading = 0; heading < kDirections; ++heading)
    for (int rel = 0; rel < kDirections; ++rel) staticCost_[heading][rel] = table.cost(rel, rotateDir(heading, rel));
  heightTerm_ = params.beta != 0 && world.hasHeights();
  for (int heading = 0; heading < kDirections; ++heading)
    for (int rel = 0; rel < kDirections; ++rel) {
      const int dir = (heading + rel) & 7;
      offset_[heading][rel] = kDirRow[dir] * g_.cols + kDirCol[dir];
    }
  onBorder_.assign(static_cast<std::size_t>(g_.cellCount()), 0);
  for (int row = 0; row < g_.rows; ++row)
    for (int col = 0; col < g_.cols; ++col)
      if (row == 0 || col == 0 || row == g_.rows - 1 || col == g_.cols - 1) onBorder_[g_.index(row, col)] = 1;
  bfsParent_.assign(g_.cellCount(), -1);
  bfsSeen_.assign(g_.cellCount(), 0);
}

bool MovePolicy::enterable(const CoverageRover& r, int i) const {
  const KnowledgeMap& m = mapOf(r);
  return m.inRegion(i) && m.state(i) != CellState::Obstacle && team_.isFree(i);
}

bool MovePolicy::hasUnvisitedNeighbour(const CoverageRover& r) const {
  for (const Neighbour& n : neighbours8(g_, r.cell))
    if (enterable(r, n.index) && mapOf(r).visits(n.index) == 0) return true;
  return false;
}

int MovePolicy::costStep(CoverageRover& r) {
  // Paper 000 eq. 3: mc = α(mc_static + mc_visited·V) + β·|Δh|; the cheapest neighbour wins, ties
  // go to the first in the order straight, L45, L90, ... (rarely needed: left ≠ right). Without
  // the height term β·|Δh| is +0, which changes no sum.
  // The move every step of every run makes (a third of a study's time): the map's arrays are read
  // raw, and a cell away from the border takes its neighbours by fixed offsets.
  const KnowledgeMap& m = mapOf(r);
  const CellState* state = m.stateData();
  const std::uint32_t* visits = m.visitsData();
  const std::uint8_t* region = m.regionData();
  const int* occupant = team_.occupantData();
  const double alpha = p_.alpha, mcVisited = p_.mcVisited, beta = p_.beta;
  const double hCur = heightTerm_ ? world_.height(r.cell) : 0.0;
  const std::array<double, 8>& staticCost = staticCost_[r.heading];
  const std::array<int, 8>& offset = offset_[r.heading];
  int best = -1;
  double bestCost = std::numeric_limits<double>::infinity();
  double blockedStraightCost = std::numeric_limits<double>::infinity();
  auto consider = [&](int i, int rel) {
    if (region && !region[i]) return;
    double cost = alpha * (staticCost[rel] + mcVisited * visits[i]);
    if (heightTerm_) cost += beta * std::fabs(world_.height(i) - hCur);
    if (state[i] == CellState::Obstacle) {
      if (rel == 0) blockedStraightCost = cost;
      return;
    }
    if (occupant[i] != TeamOccupancy::kNoRover) return;
    if (cost < bestCost) bestCost = cost, best = i;
  };
  if (!onBorder_[static_cast<std::size_t>(r.cell)]) {
    for (int rel = 0; rel < kDirections; ++rel) consider(r.cell + offset[rel], rel);
  } else {
    for (const Neighbour& n : neighbours8(g_, r.cell, r.heading)) consider(n.index, (n.dir - r.heading) & 7);
  }
  // "When an obstacle is sensed ahead" and it is what stops the rover going straight on, follow
  // its contour instead of turning away (paper 002 §2.2, obstacle circumnavigation).
  if (p_.circumnavigate && blockedStraightCost < bestCost && worthCircling(r)) {
    r.circling = true;
    r.lineDir = r.heading;
    r.lineOrigin = r.cell;
    r.circleSteps = 0;
    int next = contourStep(r, true);
    if (next >= 0) return next;
    r.circling = false;
  }
  return best;
}

bool MovePolicy::worthCircling(const CoverageRover& r) const {
  // Only lanes (orthogonal headings) are followed round an obstacle, only when the line continues
  // into cells not yet visited beyond it, and never again from a point where circling was given
  // up: otherwise a rover circles one rock forever, or traces diagonal lanes that leave gaps.
  if (isDiagonal(r.heading) || r.cell == r.abandonedOrigin) return false;
  const KnowledgeMap& m = mapOf(r);
  CellIndex c = g_.cell(r.cell);
  for (int k = 1;; ++k) {
    int row = c.row + k * kDirRow[r.heading], col = c.col + k * kDirCol[r.heading];
    if (!g_.contains(row, col) || !m.inRegion(g_.index(row, col))) return false;
    CellState s = m.state(g_.index(row, col));
    if (s != CellState::Obstacle) return s != CellState::Visited;
  }
}

int MovePolicy::contourStep(CoverageRover& r, bool first) const {
  // Right-hand contour following on the 8-grid: on the first step turn left away from the
  // obstacle ahead (straight, L45, L90, ...); afterwards try to turn right as far as possible
  // (R90, R45, straight, L45, ...), which keeps the obstacle on the right.
  // A candidate must touch a known obstacle: without that, "turn right as far as possible" spins
  // in open space once the rover has passed the obstacle's last cell.
  const int firstDir = first ? r.heading : r.heading - 2;
  for (const Neighbour& n : neighbours8(g_, r.cell, firstDir))
    if (enterable(r, n.index) && touchesKnownObstacle(mapOf(r), n.index)) return n.index;
  return -1;
}

bool MovePolicy::touchesKnownObstacle(const KnowledgeMap& m, int cell) const {
  for (const Neighbour& n : neighbours8(g_, cell))
    if (m.state(n.index) == CellState::Obstacle) return true;
  return false;
}

int MovePolicy::afterContourMove(CoverageRover& r) {
  ++r.circleSteps;
  CellIndex o = g_.cell(r.lineOrigin), c = g_.cell(r.cell);
  int dr = c.row - o.row, dc = c.col - o.col;
  int lr = kDirRow[r.lineDir], lc = kDirCol[r.lineDir];
  bool onLine = dr * lc - dc * lr == 0 && dr * lr + dc * lc > 0;
  if (onLine) {
    // Regained the original line beyond the obstacle: turn back onto it (a spot turn).
    const int from = r.heading;
    r.heading = r.lineDir;
    r.circling = false;
    return from;
  }
  if (r.cell == r.lineOrigin || r.circleSteps > 4 * (g_.rows + g_.cols)) {
    r.circling = false;  // went all the way round (obstacle touches the border): give up
    r.abandonedOrigin = r.lineOrigin;
  }
  return -1;
}

int MovePolicy::frontierStep(CoverageRover& r) {
  // Ours (SPEC §1 frontier): every neighbour is visited, so walk the shortest known path to the
  // nearest cell not yet entered; re-plan when the path is blocked by a team mate.
  // The path's next cell must still neighbour the rover's: under localisation error a bump
  // leaves the rover where it was and a loop closure moves its believed cell, either of which
  // puts the rest of the path out of step.
  if (r.planPos < r.plan.size() && enterable(r, r.plan[r.planPos])) {
    const CellIndex a = g_.cell(r.cell), b = g_.cell(r.plan[r.planPos]);
    if (std::max(std::abs(a.row - b.row), std::abs(a.col - b.col)) == 1) return r.plan[r.planPos++];
  }
  int next = bfsToFrontier(r, false);
  if (next >= 0 && !team_.isFree(next)) next = bfsToFrontier(r, true);
  return next;
}

int MovePolicy::bfsToFrontier(CoverageRover& r, bool avoidRovers) {
  const KnowledgeMap& m = mapOf(r);
  if (++bfsStamp_ == 0) std::fill(bfsSeen_.begin(), bfsSeen_.end(), 0), bfsStamp_ = 1;
  bfsQueue_.clear();
  bfsQueue_.push_back(r.cell);
  bfsSeen_[r.cell] = bfsStamp_;
  bfsParent_[r.cell] = -1;
  int target = -1;
  for (std::size_t head = 0; head < bfsQueue_.size() && target < 0; ++head) {
    const int cur = bfsQueue_[head];
    for (const Neighbour& n : neighbours8(g_, cur)) {
      const int i = n.index;
      if (bfsSeen_[i] == bfsStamp_ || !m.inRegion(i)) continue;
      CellState s = m.state(i);
      if (s == CellState::Obstacle || s == CellState::Unknown) continue;  // known-free only
      if (avoidRovers && !team_.isFree(i)) continue;
      bfsSeen_[i] = bfsStamp_;
      bfsParent_[i] = cur;
      if (s == CellState::Free) {
        target = i;
        break;
      }
      bfsQueue_.push_back(i);
    }
  }
  r.plan.clear();
  r.planPos = 0;
  if (target < 0) {
    if (!avoidRovers) {
      r.done = true;  // nothing reachable is left unexplored: regions sealed off are reported
      r.doneReason = StopReason::NothingLeft;
    }
    return -1;
  }
  for (int i = target; i != r.cell; i = bfsParent_[i]) r.plan.push_back(i);
  std::reverse(r.plan.begin(), r.plan.end());
  r.planPos = 1;
  return r.plan[0];
}

bool MovePolicy::walledIn(const CoverageRover& r) const {
  const KnowledgeMap& m = mapOf(r);
  for (const Neighbour& n : neighbours8(g_, r.cell))
    if (m.inRegion(n.index) && m.state(n.index) != CellState::Obstacle) return false;
  return true;
}

}  // namespace rover::coverage
