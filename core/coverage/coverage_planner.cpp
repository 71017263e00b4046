#include "core/coverage/coverage_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/coverage/dead_reckoning.hpp"
#include "core/coverage/energy.hpp"
#include "core/grid/direction.hpp"

namespace rover::coverage {

std::vector<StartCell> randomStarts(const World& world, int count, std::uint64_t seed) {
  std::vector<int> sizes;
  std::vector<int> label = freeComponents(world, sizes);
  if (sizes.empty())
    throw Error(ErrorCode::InvalidInput, "obstacles", "the world has no free cell");
  int largest = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  std::vector<int> pool;
  for (int i = 0; i < static_cast<int>(label.size()); ++i)
    if (label[i] == largest) pool.push_back(i);
  if (count < 1 || count > static_cast<int>(pool.size()))
    throw Error(ErrorCode::InvalidInput, "rovers",
                "cannot place " + std::to_string(count) + " rovers on " +
                    std::to_string(pool.size()) + " connected free cells");
  Rng rng(deriveSeed(seed, 2));
  std::vector<StartCell> starts;
  for (int k = 0; k < count; ++k) {
    std::size_t j = k + rng.below(pool.size() - k);  // partial Fisher–Yates
    std::swap(pool[k], pool[j]);
    starts.push_back({pool[k], static_cast<int>(rng.below(8))});
  }
  return starts;
}

namespace {

constexpr int kNoRover = -1;

struct RoverRun {
  int cell = 0;
  int heading = 0;
  int mapId = 0;
  bool done = false;
  StopReason doneReason = StopReason::GoalReached;
  RoverTrack track;
  // Obstacle circumnavigation (paper 002 §2.2): the line being followed when an obstacle blocked
  // it, and where; the contour is followed with the obstacle on the right until the line is
  // regained.
  bool circling = false;
  int lineDir = 0;
  int lineOrigin = 0;
  int circleSteps = 0;
  int abandonedOrigin = -1;
  // Frontier mode: the known path being walked to the nearest unexplored cell.
  std::vector<int> plan;
  std::size_t planPos = 0;
  // Localisation error (dead_reckoning.hpp), when modelled: the cell the rover truly stands in and
  // its dead reckoning; `cell` and `heading` above are then the believed pose.
  int trueCell = 0;
  std::optional<DeadReckoning> odo;
  double errorSum = 0;
};

// Localisation error: the true side of one move that happened.
struct TrueMove {
  int from = 0, to = 0;   // true cells
  double horizontal = 0;  // metres truly driven
};

// Direction of a one-cell move (dr, dc) in -1..1; -1 for (0, 0).
int moveDir(int dr, int dc) {
  for (int d = 0; d < kDirections; ++d)
    if (kDirRow[d] == dr && kDirCol[d] == dc) return d;
  return -1;
}

class Engine {
 public:
  Engine(const World& world, const std::vector<StartCell>& starts, const CoverageParams& params,
         EventSink* sink, const CancelToken* cancel)
      : world_(world),
        g_(world.geometry()),
        p_(params),
        table_(params.table()),
        sink_(sink),
        cancel_(cancel),
        loc_(params.localisation.active()),
        occupant_(g_.cellCount(), kNoRover) {
    setUp(starts);
  }

  CoverageResult run();

 private:
  void setUp(const std::vector<StartCell>& starts);
  KnowledgeMap& mapOf(const RoverRun& r) { return maps_[r.mapId]; }
  // In the grid, in the rover's region, not a known obstacle, and not held by another rover.
  bool enterable(const RoverRun& r, int row, int col) const;
  void senseAround(RoverRun& r);
  bool hasUnvisitedNeighbour(const RoverRun& r) const;
  int choose(RoverRun& r);
  int costStep(RoverRun& r);
  int contourStep(RoverRun& r, bool first);
  bool touchesKnownObstacle(const RoverRun& r, int row, int col) const;
  bool worthCircling(const RoverRun& r) const;
  int frontierStep(RoverRun& r);
  int bfsToFrontier(RoverRun& r, bool avoidRovers);
  void moveTo(RoverRun& r, int next, const TrueMove* truth);
  // Localisation error: drives the true rover toward `next`.
  enum class Drive { Moved, Bumped, Blocked /* a team mate truly in the way */ };
  Drive driveTrue(RoverRun& r, int next, std::int64_t step, TrueMove& out);
  void closeLoop(RoverRun& r);
  Eigen::Vector2d believedPos(const RoverRun& r) const {
    return cellToLocal(g_, g_.cell(r.cell)) + r.odo->offset();
  }
  Eigen::Vector2d truePos(const RoverRun& r) const { return believedPos(r) + r.odo->error(); }
  void recordPose(RoverRun& r);
  // No neighbour the rover's map lets it enter, team mates aside.
  bool walledIn(const RoverRun& r) const;
  void summariseLocalisation(CoverageResult& res) const;
  int trueVisitedTotal() const { return loc_ ? trueVisitedCount_ : visitedTotal(); }
  void afterContourMove(RoverRun& r);
  int visitedTotal() const;
  bool teamGoalReached() const;
  void emit(std::int64_t step);

  const World& world_;
  const GridGeometry& g_;
  CoverageParams p_;
  MotionCostTable table_;
  EventSink* sink_;
  const CancelToken* cancel_;
  const bool loc_;  // localisation error modelled (dead_reckoning.hpp)
  std::vector<int> occupant_;  // by believed cell
  std::vector<KnowledgeMap> maps_;
  std::vector<RoverRun> rovers_;
  std::vector<int> region_;
  std::vector<std::uint8_t> reachable_;
  int reachableCount_ = 0;
  std::vector<CellUpdate> changes_;
  std::vector<RoverPose> poses_;
  std::vector<CurvePoint> curve_;
  // Breadth-first search scratch, reused between searches (a stamp instead of clearing).
  std::vector<int> bfsParent_;
  std::vector<std::uint32_t> bfsSeen_;
  std::uint32_t bfsStamp_ = 0;
  std::vector<int> bfsQueue_;
  // Localisation error: true occupancy and visits, loop-closure bookkeeping, bumps.
  std::vector<int> trueOccupant_;
  std::vector<std::uint8_t> trueVisited_;
  int trueVisitedCount_ = 0;
  std::vector<std::int64_t> lastEntered_;  // team move count at a cell's last entry
  std::int64_t teamMoves_ = 0;
  std::vector<Bump> bumps_;
  int bumpCount_ = 0;
};

void Engine::setUp(const std::vector<StartCell>& starts) {
  validateWorld(world_);
  validateCoverageParams(p_);
  const int n = g_.cellCount();
  if (starts.empty() || starts.size() > 64)
    throw Error(ErrorCode::InvalidInput, "rovers", "between 1 and 64 rovers are supported");
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const std::string field = "rovers[" + std::to_string(k) + "]";
    const StartCell& s = starts[k];
    if (s.cell < 0 || s.cell >= n)
      throw Error(ErrorCode::InvalidInput, field, field + ": start is outside the grid");
    if (world_.isObstacle(s.cell))
      throw Error(ErrorCode::InvalidInput, field, field + ": start is on an obstacle");
    if (s.heading < 0 || s.heading > 7)
      throw Error(ErrorCode::InvalidInput, field, field + ": heading must be a direction 0..7");
    if (occupant_[s.cell] != kNoRover)
      throw Error(ErrorCode::InvalidInput, field, field + ": two rovers start on one cell");
    occupant_[s.cell] = static_cast<int>(k);
  }

  const int count = static_cast<int>(starts.size());
  if (p_.mode == TeamMode::Voronoi && count > 1) {
    // Paper 002 §2.3 "environment sharing": each cell goes to the nearest initial rover position
    // (Euclidean, in cells); ties go to the lower rover index.
    region_.assign(n, 0);
    for (int i = 0; i < n; ++i) {
      CellIndex c = g_.cell(i);
      long best = std::numeric_limits<long>::max();
      for (int k = 0; k < count; ++k) {
        CellIndex s = g_.cell(starts[k].cell);
        long dr = c.row - s.row, dc = c.col - s.col;
        long d2 = dr * dr + dc * dc;
        if (d2 < best) best = d2, region_[i] = k;
      }
    }
    for (int k = 0; k < count; ++k) {
      std::vector<std::uint8_t> mask(n);
      for (int i = 0; i < n; ++i) mask[i] = region_[i] == k;
      std::vector<std::uint8_t> reach = reachableCells(world_, {starts[k].cell}, mask);
      if (reachable_.empty()) reachable_.assign(n, 0);
      for (int i = 0; i < n; ++i) reachable_[i] |= reach[i];
      maps_.emplace_back(g_, std::move(mask));
    }
  } else {
    maps_.emplace_back(g_);
    std::vector<int> cells;
    for (const auto& s : starts) cells.push_back(s.cell);
    reachable_ = reachableCells(world_, cells);
  }
  reachableCount_ = static_cast<int>(std::count(reachable_.begin(), reachable_.end(), 1));

  for (int k = 0; k < count; ++k) {
    RoverRun r;
    r.cell = starts[k].cell;
    r.heading = starts[k].heading;
    r.mapId = maps_.size() > 1 ? k : 0;
    r.track.cells.push_back(r.cell);
    r.trueCell = r.cell;
    if (loc_) r.odo.emplace(p_.localisation, p_.localisation.seed, k);
    rovers_.push_back(std::move(r));
  }
  if (loc_) {
    trueOccupant_ = occupant_;
    trueVisited_.assign(n, 0);
    if (p_.localisation.loopClosure) lastEntered_.assign(n, 0);
    for (auto& r : rovers_) {
      trueVisitedCount_ += !trueVisited_[r.trueCell];
      trueVisited_[r.trueCell] = 1;
      r.track.truePoints.push_back(truePos(r));
      r.track.believedPoints.push_back(believedPos(r));
    }
  }
  for (auto& r : rovers_) {
    mapOf(r).visit(r.cell);
    if (sink_) changes_.push_back({r.cell, std::uint8_t(CellState::Visited), 1});
    senseAround(r);
  }
  bfsParent_.assign(n, -1);
  bfsSeen_.assign(n, 0);
}

bool Engine::enterable(const RoverRun& r, int row, int col) const {
  if (!g_.contains(row, col)) return false;
  int i = g_.index(row, col);
  const KnowledgeMap& m = maps_[r.mapId];
  return m.inRegion(i) && m.state(i) != CellState::Obstacle && occupant_[i] == kNoRover;
}

void Engine::senseAround(RoverRun& r) {
  // Myopic, omnidirectional sensing: every cell within Chebyshev radius R (SPEC §1 step 1).
  // With localisation error the truth around the true cell is written around the believed one
  // (dead_reckoning.hpp); beyond the field's edge is an obstacle.
  KnowledgeMap& m = mapOf(r);
  CellIndex c = g_.cell(r.cell);
  CellIndex t = g_.cell(loc_ ? r.trueCell : r.cell);
  const int R = p_.senseRadius;
  for (int dr = -R; dr <= R; ++dr) {
    for (int dc = -R; dc <= R; ++dc) {
      int row = c.row + dr, col = c.col + dc;
      if (!g_.contains(row, col)) continue;
      int i = g_.index(row, col);
      if (!m.inRegion(i)) continue;
      const int tr = t.row + dr, tc = t.col + dc;
      const bool obstacle = !g_.contains(tr, tc) || world_.isObstacle(g_.index(tr, tc));
      if (m.sense(i, obstacle) && sink_)
        changes_.push_back({i, std::uint8_t(m.state(i)), 0});
    }
  }
}

bool Engine::hasUnvisitedNeighbour(const RoverRun& r) const {
  CellIndex c = g_.cell(r.cell);
  const KnowledgeMap& m = maps_[r.mapId];
  for (int d = 0; d < kDirections; ++d) {
    int row = c.row + kDirRow[d], col = c.col + kDirCol[d];
    if (enterable(r, row, col) && m.visits(g_.index(row, col)) == 0) return true;
  }
  return false;
}

int Engine::choose(RoverRun& r) {
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

int Engine::costStep(RoverRun& r) {
  // Paper 000 eq. 3: mc = α(mc_static + mc_visited·V) + β·|Δh|; the cheapest neighbour wins, ties
  // go to the first in the order straight, L45, L90, ... (rarely needed: left ≠ right).
  const KnowledgeMap& m = mapOf(r);
  CellIndex c = g_.cell(r.cell);
  const double hCur = world_.height(r.cell);
  int best = -1;
  double bestCost = std::numeric_limits<double>::infinity();
  double blockedStraightCost = std::numeric_limits<double>::infinity();
  for (int rel = 0; rel < kDirections; ++rel) {
    int dir = rotateDir(r.heading, rel);
    int row = c.row + kDirRow[dir], col = c.col + kDirCol[dir];
    if (!g_.contains(row, col)) continue;
    int i = g_.index(row, col);
    if (!m.inRegion(i)) continue;
    double cost = p_.alpha * (table_.cost(rel, dir) + p_.mcVisited * m.visits(i)) +
                  p_.beta * std::fabs(world_.height(i) - hCur);
    if (m.state(i) == CellState::Obstacle) {
      if (rel == 0) blockedStraightCost = cost;
      continue;
    }
    if (occupant_[i] != kNoRover) continue;
    if (cost < bestCost) bestCost = cost, best = i;
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

bool Engine::worthCircling(const RoverRun& r) const {
  // Only lanes (orthogonal headings) are followed round an obstacle, only when the line continues
  // into cells not yet visited beyond it, and never again from a point where circling was given
  // up: otherwise a rover circles one rock forever, or traces diagonal lanes that leave gaps.
  if (isDiagonal(r.heading) || r.cell == r.abandonedOrigin) return false;
  const KnowledgeMap& m = maps_[r.mapId];
  CellIndex c = g_.cell(r.cell);
  for (int k = 1;; ++k) {
    int row = c.row + k * kDirRow[r.heading], col = c.col + k * kDirCol[r.heading];
    if (!g_.contains(row, col) || !m.inRegion(g_.index(row, col))) return false;
    CellState s = m.state(g_.index(row, col));
    if (s != CellState::Obstacle) return s != CellState::Visited;
  }
}

int Engine::contourStep(RoverRun& r, bool first) {
  // Right-hand contour following on the 8-grid: on the first step turn left away from the
  // obstacle ahead (straight, L45, L90, ...); afterwards try to turn right as far as possible
  // (R90, R45, straight, L45, ...), which keeps the obstacle on the right.
  // A candidate must touch a known obstacle: without that, "turn right as far as possible" spins
  // in open space once the rover has passed the obstacle's last cell.
  static constexpr int kFirst[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static constexpr int kFollow[8] = {6, 7, 0, 1, 2, 3, 4, 5};
  const int* order = first ? kFirst : kFollow;
  CellIndex c = g_.cell(r.cell);
  for (int k = 0; k < kDirections; ++k) {
    int dir = rotateDir(r.heading, order[k]);
    int row = c.row + kDirRow[dir], col = c.col + kDirCol[dir];
    if (enterable(r, row, col) && touchesKnownObstacle(r, row, col)) return g_.index(row, col);
  }
  return -1;
}

bool Engine::touchesKnownObstacle(const RoverRun& r, int row, int col) const {
  const KnowledgeMap& m = maps_[r.mapId];
  for (int d = 0; d < kDirections; ++d) {
    int rr = row + kDirRow[d], cc = col + kDirCol[d];
    if (g_.contains(rr, cc) && m.state(g_.index(rr, cc)) == CellState::Obstacle) return true;
  }
  return false;
}

void Engine::afterContourMove(RoverRun& r) {
  ++r.circleSteps;
  CellIndex o = g_.cell(r.lineOrigin), c = g_.cell(r.cell);
  int dr = c.row - o.row, dc = c.col - o.col;
  int lr = kDirRow[r.lineDir], lc = kDirCol[r.lineDir];
  bool onLine = dr * lc - dc * lr == 0 && dr * lr + dc * lc > 0;
  if (onLine) {
    // Regained the original line beyond the obstacle: turn back onto it (a spot turn).
    r.track.energyJ += turnEnergy(p_.energy, r.heading, r.lineDir);
    r.heading = r.lineDir;
    r.circling = false;
  } else if (r.cell == r.lineOrigin || r.circleSteps > 4 * (g_.rows + g_.cols)) {
    r.circling = false;  // went all the way round (obstacle touches the border): give up
    r.abandonedOrigin = r.lineOrigin;
  }
}

int Engine::frontierStep(RoverRun& r) {
  // Ours (SPEC §1 frontier): every neighbour is visited, so walk the shortest known path to the
  // nearest cell not yet entered; re-plan when the path is blocked by a team mate.
  if (r.planPos < r.plan.size()) {
    CellIndex nxt = g_.cell(r.plan[r.planPos]);
    if (enterable(r, nxt.row, nxt.col)) return r.plan[r.planPos++];
  }
  int next = bfsToFrontier(r, false);
  if (next >= 0 && occupant_[next] != kNoRover) next = bfsToFrontier(r, true);
  return next;
}

int Engine::bfsToFrontier(RoverRun& r, bool avoidRovers) {
  const KnowledgeMap& m = mapOf(r);
  if (++bfsStamp_ == 0) std::fill(bfsSeen_.begin(), bfsSeen_.end(), 0), bfsStamp_ = 1;
  bfsQueue_.clear();
  bfsQueue_.push_back(r.cell);
  bfsSeen_[r.cell] = bfsStamp_;
  bfsParent_[r.cell] = -1;
  int target = -1;
  for (std::size_t head = 0; head < bfsQueue_.size() && target < 0; ++head) {
    int cur = bfsQueue_[head];
    CellIndex c = g_.cell(cur);
    for (int d = 0; d < kDirections; ++d) {
      int row = c.row + kDirRow[d], col = c.col + kDirCol[d];
      if (!g_.contains(row, col)) continue;
      int i = g_.index(row, col);
      if (bfsSeen_[i] == bfsStamp_ || !m.inRegion(i)) continue;
      CellState s = m.state(i);
      if (s == CellState::Obstacle || s == CellState::Unknown) continue;  // known-free only
      if (avoidRovers && occupant_[i] != kNoRover) continue;
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

Engine::Drive Engine::driveTrue(RoverRun& r, int next, std::int64_t step, TrueMove& out) {
  DeadReckoning& odo = *r.odo;
  const CellIndex a = g_.cell(r.cell), b = g_.cell(next);
  const int dir = moveDir(b.row - a.row, b.col - a.col);
  // Commanded: from the believed position to the centre of `next` (local y is north, rows south).
  const Eigen::Vector2d step2((b.col - a.col) * g_.cellWidth, (a.row - b.row) * g_.cellWidth);
  const bool centred = odo.offset().x() == 0 && odo.offset().y() == 0;
  const Eigen::Vector2d d = step2 - odo.offset();
  const double length =
      centred ? g_.cellWidth * (isDiagonal(dir) ? std::numbers::sqrt2 : 1.0) : d.norm();
  const Eigen::Vector2d from = truePos(r);
  const Eigen::Vector2d D = odo.drive(d, length, [&](const Eigen::Vector2d& move) {
    auto end = localToCell(g_, from + move);
    if (!end) return 0.0;
    const double dh = world_.height(g_.index(*end)) - world_.height(r.trueCell);
    return std::atan2(dh, length) * 180.0 / std::numbers::pi;
  });
  // Where the rover truly ends: the new believed centre plus the new error (as recordPose sees it).
  const Eigen::Vector2d newError = odo.error() + (D - d);
  const Eigen::Vector2d to = cellToLocal(g_, b) + newError;
  const auto end = localToCell(g_, to);
  const int me = static_cast<int>(&r - rovers_.data());
  if (end && !world_.isObstacle(g_.index(*end))) {
    const int e = g_.index(*end);
    if (trueOccupant_[e] != kNoRover && trueOccupant_[e] != me) return Drive::Blocked;
    out = {r.trueCell, e, odo.travelled()};
    odo.arrived(d, D);
    trueOccupant_[r.trueCell] = kNoRover;
    trueOccupant_[e] = me;
    r.trueCell = e;
    trueVisitedCount_ += !trueVisited_[e];
    trueVisited_[e] = 1;
    return Drive::Moved;
  }
  // A bump: the rover stays, faces the cell it tried and marks it an obstacle in its map.
  ++r.track.bumps;
  ++bumpCount_;
  if (bumps_.size() < kMaxBumpRecords) bumps_.push_back({me, step, next, from, !end});
  if (mapOf(r).markObstacle(next) && sink_)
    changes_.push_back({next, std::uint8_t(CellState::Obstacle), 0});
  r.track.energyJ += turnEnergy(p_.energy, r.heading, dir);
  r.heading = dir;
  r.circling = false;
  return Drive::Bumped;
}

void Engine::closeLoop(RoverRun& r) {
  DeadReckoning& odo = *r.odo;
  const Eigen::Vector2d oldError = odo.error();
  const double oldHeading = odo.headingError();
  const Eigen::Vector2d believed = believedPos(r) + odo.closeLoop(p_.localisation.loopClosureKeep);
  const auto cell = localToCell(g_, believed);
  const int i = cell ? g_.index(*cell) : -1;
  KnowledgeMap& m = mapOf(r);
  if (i < 0 || (i != r.cell && (!m.inRegion(i) || m.state(i) == CellState::Obstacle ||
                                occupant_[i] != kNoRover))) {
    odo.undoLoop(oldError, oldHeading);  // waits for the next revisit
    return;
  }
  if (i != r.cell) {
    occupant_[r.cell] = kNoRover;
    occupant_[i] = static_cast<int>(&r - rovers_.data());
    r.cell = i;
    m.visit(i);
    lastEntered_[i] = teamMoves_;
    if (sink_) changes_.push_back({i, std::uint8_t(CellState::Visited), m.visits(i)});
  }
  odo.setOffset(believed - cellToLocal(g_, *cell));
  ++r.track.loopClosures;
}

bool Engine::walledIn(const RoverRun& r) const {
  const KnowledgeMap& m = maps_[r.mapId];
  const CellIndex c = g_.cell(r.cell);
  for (int d = 0; d < kDirections; ++d) {
    const int row = c.row + kDirRow[d], col = c.col + kDirCol[d];
    if (!g_.contains(row, col)) continue;
    const int i = g_.index(row, col);
    if (m.inRegion(i) && m.state(i) != CellState::Obstacle) return false;
  }
  return true;
}

void Engine::recordPose(RoverRun& r) {
  const double error = r.odo->error().norm();
  r.track.truePoints.push_back(truePos(r));
  r.track.believedPoints.push_back(believedPos(r));
  r.track.errorM.push_back(static_cast<float>(error));
  r.errorSum += error;
}

void Engine::moveTo(RoverRun& r, int next, const TrueMove* truth) {
  KnowledgeMap& m = mapOf(r);
  CellIndex a = g_.cell(r.cell), b = g_.cell(next);
  int dir = moveDir(b.row - a.row, b.col - a.col);
  double horizontal = g_.cellWidth * (isDiagonal(dir) ? std::numbers::sqrt2 : 1.0);
  double dh = world_.height(next) - world_.height(r.cell);
  if (truth) {
    // Energy and pitch of the motion that truly happened.
    horizontal = truth->horizontal;
    dh = world_.height(truth->to) - world_.height(truth->from);
  }
  // A revisit of a cell last entered long enough ago closes a loop (dead_reckoning.hpp).
  const bool loop = truth && p_.localisation.loopClosure && m.visits(next) > 0 &&
                    teamMoves_ + 1 - lastEntered_[next] >= p_.localisation.loopClosureGap;
  double pitchDeg = std::atan(std::fabs(dh) / horizontal) * 180.0 / std::numbers::pi;

  RoverTrack& t = r.track;
  t.energyJ += turnEnergy(p_.energy, r.heading, dir) + forwardEnergy(p_.energy, horizontal, dh);
  t.distanceM += horizontal;
  t.maxPitchDeg = std::max(t.maxPitchDeg, pitchDeg);
  t.pitchDeg.push_back(static_cast<float>(pitchDeg));
  t.cells.push_back(next);
  ++t.moves;
  t.revisits += m.visit(next);
  if (sink_) changes_.push_back({next, std::uint8_t(CellState::Visited), m.visits(next)});

  occupant_[r.cell] = kNoRover;
  occupant_[next] = static_cast<int>(&r - rovers_.data());
  r.cell = next;
  r.heading = dir;
  if (truth) {
    ++teamMoves_;
    if (p_.localisation.loopClosure) lastEntered_[next] = teamMoves_;
    if (loop) closeLoop(r);
    recordPose(r);
  }
}

int Engine::visitedTotal() const {
  int v = 0;
  for (const auto& m : maps_) v += m.visitedCount();
  return v;
}

bool Engine::teamGoalReached() const {
  return maps_.size() == 1 && maps_[0].goalReached(p_.coverage);
}

void Engine::emit(std::int64_t step) {
  if (!sink_) return;
  if (!changes_.empty()) sink_->cellsChanged(changes_);
  changes_.clear();
  poses_.clear();
  for (std::size_t k = 0; k < rovers_.size(); ++k) {
    const RoverRun& r = rovers_[k];
    if (loc_) {
      const Eigen::Vector2d t = truePos(r), b = believedPos(r);
      poses_.push_back({static_cast<int>(k), t.x(), t.y(), dirToRadians(r.heading), true, b.x(), b.y()});
      continue;
    }
    Eigen::Vector2d xy = cellToLocal(g_, g_.cell(r.cell));
    poses_.push_back({static_cast<int>(k), xy.x(), xy.y(), dirToRadians(r.heading)});
  }
  sink_->roverPoses(step, poses_);
  double needed = 0;
  for (const auto& m : maps_)
    needed += std::max(1.0, std::ceil(p_.coverage * (m.regionCells() - m.knownObstacles()) - 1e-9));
  Progress pr;
  pr.step = step;
  pr.fraction = std::min(1.0, visitedTotal() / needed);
  pr.coverage = static_cast<double>(visitedTotal()) / world_.freeCount();
  pr.moves = curve_.empty() ? 0 : curve_.back().moves;
  sink_->progress(pr);
}

CoverageResult Engine::run() {
  CoverageResult res;
  const std::int64_t budget = p_.stepBudget(g_.cellCount());
  std::int64_t moves = 0, step = 0;
  // Voronoi rovers stop one by one; an overlap team stops together.
  auto checkRegionGoal = [&](RoverRun& r) {
    if (maps_.size() > 1 && !r.done && mapOf(r).goalReached(p_.coverage)) {
      r.done = true;
      r.doneReason = StopReason::GoalReached;
    }
  };
  for (auto& r : rovers_) checkRegionGoal(r);
  bool goal = teamGoalReached();
  curve_.push_back({0, 0, visitedTotal(), trueVisitedTotal()});
  emit(0);

  StopReason stop = StopReason::StepBudget;
  while (true) {
    bool allDone = std::all_of(rovers_.begin(), rovers_.end(), [](auto& r) { return r.done; });
    if (goal || allDone) {
      bool anyNothingLeft = std::any_of(rovers_.begin(), rovers_.end(), [](auto& r) {
        return r.done && r.doneReason == StopReason::NothingLeft;
      });
      stop = goal || !anyNothingLeft ? StopReason::GoalReached : StopReason::NothingLeft;
      break;
    }
    if (cancel_ && cancel_->cancelled()) {
      stop = StopReason::Cancelled;
      break;
    }
    if (step >= budget) break;
    ++step;
    for (auto& r : rovers_) {
      if (r.done) continue;
      int next = choose(r);
      if (r.done) continue;
      if (next < 0) {
        if (loc_ && walledIn(r)) {
          // Under localisation error the map itself can wall a rover in (bumps and smeared
          // obstacles all round): it can never move again, so it stops.
          r.done = true;
          r.doneReason = StopReason::NothingLeft;
          continue;
        }
        ++r.track.waits;  // boxed in by team mates this step
        continue;
      }
      bool wasCircling = r.circling;
      TrueMove truth;
      if (const Drive drive = loc_ ? driveTrue(r, next, step, truth) : Drive::Moved;
          drive != Drive::Moved) {
        // Not moved: a team mate truly in the way, or a bump (the map changed: the goal, which
        // counts known obstacles, may now be met).
        if (drive == Drive::Blocked) ++r.track.waits;
        checkRegionGoal(r);
        if (teamGoalReached()) {
          goal = true;
          break;
        }
        continue;
      }
      moveTo(r, next, loc_ ? &truth : nullptr);
      if (wasCircling && r.circling) afterContourMove(r);
      ++moves;
      senseAround(r);
      checkRegionGoal(r);
      if (teamGoalReached()) {
        goal = true;
        break;
      }
    }
    curve_.push_back({step, moves, visitedTotal(), trueVisitedTotal()});
    emit(step);
  }

  res.stop = stop;
  CoverageMetrics& mt = res.metrics;
  mt.cells = g_.cellCount();
  mt.freeCells = world_.freeCount();
  mt.reachableCells = reachableCount_;
  mt.unreachableCells = mt.freeCells - reachableCount_;
  mt.visitedCells = visitedTotal();
  mt.coverage = static_cast<double>(mt.visitedCells) / mt.freeCells;
  mt.coverageReachable = static_cast<double>(mt.visitedCells) / std::max(1, reachableCount_);
  mt.steps = step;
  for (const auto& r : rovers_) {
    mt.moves += r.track.moves;
    mt.makespan = std::max(mt.makespan, r.track.moves);
    mt.distanceM += r.track.distanceM;
    mt.energyJ += r.track.energyJ;
    mt.maxPitchDeg = std::max(mt.maxPitchDeg, r.track.maxPitchDeg);
    mt.revisits += r.track.revisits;
    res.rovers.push_back(r.track);
  }
  mt.pathLengthRatio = static_cast<double>(mt.moves) / mt.cells;
  mt.makespanRatio = static_cast<double>(mt.makespan) / mt.cells;
  res.curve = std::move(curve_);
  res.region = std::move(region_);
  // The team's view of the grid: each cell from the map that owns it.
  res.finalStates.assign(g_.cellCount(), CellState::Unknown);
  res.finalVisits.assign(g_.cellCount(), 0);
  for (int i = 0; i < g_.cellCount(); ++i) {
    const KnowledgeMap& m = maps_[maps_.size() > 1 ? res.region[i] : 0];
    res.finalStates[i] = m.state(i);
    res.finalVisits[i] = m.visits(i);
  }
  if (loc_) summariseLocalisation(res);
  return res;
}

void Engine::summariseLocalisation(CoverageResult& res) const {
  CoverageMetrics& mt = res.metrics;
  mt.localisation = true;
  mt.trueVisitedCells = trueVisitedCount_;
  mt.trueCoverage = static_cast<double>(trueVisitedCount_) / mt.freeCells;
  mt.bumps = bumpCount_;
  double errorSum = 0, finalSum = 0;
  std::size_t samples = 0;
  for (std::size_t k = 0; k < rovers_.size(); ++k) {
    const RoverRun& r = rovers_[k];
    RoverTrack& t = res.rovers[k];
    errorSum += r.errorSum;
    samples += t.errorM.size();
    t.maeM = t.errorM.empty() ? 0.0 : r.errorSum / static_cast<double>(t.errorM.size());
    for (float e : t.errorM) mt.maxErrorM = std::max(mt.maxErrorM, static_cast<double>(e));
    finalSum += r.odo->error().norm();
    mt.loopClosures += t.loopClosures;
  }
  // Paper 000 eq. 6 with the 1/N it omits, N = every move of every rover.
  mt.maeM = samples ? errorSum / static_cast<double>(samples) : 0.0;
  mt.finalErrorM = finalSum / static_cast<double>(rovers_.size());
  int matches = 0;
  for (int i = 0; i < g_.cellCount(); ++i) {
    const CellState s = res.finalStates[i];
    if (s == CellState::Unknown) continue;
    ++mt.mappedCells;
    matches += (s == CellState::Obstacle) == world_.isObstacle(i);
  }
  mt.mapAccuracy = mt.mappedCells ? static_cast<double>(matches) / mt.mappedCells : 1.0;
  res.bumps = bumps_;
}

}  // namespace

CoverageResult runCoverage(const World& world, const std::vector<StartCell>& starts,
                           const CoverageParams& params, EventSink* sink,
                           const CancelToken* cancel) {
  Engine engine(world, starts, params, sink, cancel);
  return engine.run();
}

std::int64_t movesToReach(const CoverageResult& result, double fraction) {
  int needed = static_cast<int>(std::ceil(fraction * result.metrics.reachableCells - 1e-9));
  for (const auto& p : result.curve)
    if (p.visited >= needed) return p.moves;
  return -1;
}

}  // namespace rover::coverage
