// The dead-reckoning plant (core/coverage/plant.hpp): the planner moves its believed pose cell by
// cell as with a perfect pose while the true rover drives the noisy displacement of
// core/coverage/dead_reckoning.hpp; sensing reads the truth around the true cell into the map
// around the believed one, a move into a true obstacle is a bump, and a revisit can close a loop.
#include <optional>
#include <numbers>

#include "core/coverage/dead_reckoning.hpp"
#include "core/coverage/plant.hpp"
#include "core/grid/direction.hpp"

namespace rover::coverage {

namespace {

class DeadReckoningPlant final : public Plant {
 public:
  DeadReckoningPlant(const World& world, const CoverageParams& params, TeamOccupancy& team,
                     Recorder& recorder, const std::vector<CoverageRover>& rovers)
      : Plant(false), world_(world), g_(world.geometry()), p_(params), team_(team), recorder_(recorder),
        trueOccupant_(team.occupants()), trueVisited_(g_.cellCount(), 0) {
    if (p_.localisation.loopClosure) lastEntered_.assign(g_.cellCount(), 0);
    for (const CoverageRover& r : rovers) {
      state_.push_back({r.cell, DeadReckoning(p_.localisation, p_.localisation.seed, r.id)});
      trueVisitedCount_ += !trueVisited_[r.cell];
      trueVisited_[r.cell] = 1;
      RoverTrack& t = recorder_.track(r.id);
      t.truePoints.push_back(truePos(r));
      t.believedPoints.push_back(believedPos(r));
    }
  }

  void sense(const CoverageRover& r) override {
    senseWindow(world_, p_.senseRadius, team_.map(r.mapId), r.cell, of(r).trueCell, recorder_);
  }
  Drive drive(CoverageRover& r, int next, int dir, std::int64_t step, Motion& motion) override;
  void arrived(CoverageRover& r) override;
  bool stopsWalledIn() const override { return true; }
  int trueVisited() const override { return trueVisitedCount_; }
  int visitedTrulyReached() const override { return 0; }
  RoverPose pose(const CoverageRover& r) const override {
    const Eigen::Vector2d t = truePos(r), b = believedPos(r);
    return {r.id, t.x(), t.y(), dirToRadians(r.heading), true, b.x(), b.y()};
  }
  void summarise(CoverageResult& res) const override;

 private:
  struct TrueState {
    int trueCell = 0;
    DeadReckoning odo;
    double errorSum = 0;
    bool loopDue = false;  // the move being booked revisits a cell long enough after its last entry
  };
  TrueState& of(const CoverageRover& r) { return state_[static_cast<std::size_t>(r.id)]; }
  const TrueState& of(const CoverageRover& r) const { return state_[static_cast<std::size_t>(r.id)]; }
  Eigen::Vector2d believedPos(const CoverageRover& r) const {
    return cellToLocal(g_, g_.cell(r.cell)) + of(r).odo.offset();
  }
  Eigen::Vector2d truePos(const CoverageRover& r) const { return believedPos(r) + of(r).odo.error(); }
  void closeLoop(CoverageRover& r);

  const World& world_;
  const GridGeometry& g_;
  const CoverageParams& p_;
  TeamOccupancy& team_;
  Recorder& recorder_;
  std::vector<TrueState> state_;
  std::vector<int> trueOccupant_;
  std::vector<std::uint8_t> trueVisited_;
  int trueVisitedCount_ = 0;
  std::vector<std::int64_t> lastEntered_;  // team move count at a cell's last entry
  std::int64_t teamMoves_ = 0;
  std::vector<Bump> bumps_;
  int bumpCount_ = 0;
};

Drive DeadReckoningPlant::drive(CoverageRover& r, int next, int dir, std::int64_t step, Motion& motion) {
  TrueState& s = of(r);
  DeadReckoning& odo = s.odo;
  const CellIndex a = g_.cell(r.cell), b = g_.cell(next);
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
    const double dh = world_.height(g_.index(*end)) - world_.height(s.trueCell);
    return std::atan2(dh, length) * 180.0 / std::numbers::pi;
  });
  // Where the rover truly ends: the new believed centre plus the new error (as pose() sees it).
  const Eigen::Vector2d newError = odo.error() + (D - d);
  const Eigen::Vector2d to = cellToLocal(g_, b) + newError;
  const auto end = localToCell(g_, to);
  if (end && !world_.isObstacle(g_.index(*end))) {
    const int e = g_.index(*end);
    if (trueOccupant_[e] != TeamOccupancy::kNoRover && trueOccupant_[e] != r.id) return Drive::Blocked;
    // Energy and pitch of the motion that truly happened.
    motion = {odo.travelled(), world_.height(e) - world_.height(s.trueCell)};
    odo.arrived(d, D);
    trueOccupant_[s.trueCell] = TeamOccupancy::kNoRover;
    trueOccupant_[e] = r.id;
    s.trueCell = e;
    trueVisitedCount_ += !trueVisited_[e];
    trueVisited_[e] = 1;
    // A revisit of a cell last entered long enough ago closes a loop (dead_reckoning.hpp).
    s.loopDue = p_.localisation.loopClosure && team_.map(r.mapId).visits(next) > 0 &&
                teamMoves_ + 1 - lastEntered_[next] >= p_.localisation.loopClosureGap;
    return Drive::Moved;
  }
  // A bump: the rover stays, faces the cell it tried and marks it an obstacle in its map.
  ++recorder_.track(r.id).bumps;
  ++bumpCount_;
  if (bumps_.size() < kMaxBumpRecords) {
    bumps_.push_back({r.id, step, next, from, !end});
    recorder_.bumped(bumps_.back());
  }
  if (team_.map(r.mapId).markObstacle(next)) recorder_.cellChanged(next, CellState::Obstacle, 0);
  recorder_.turned(r.id, r.heading, dir);
  r.heading = dir;
  r.circling = false;
  return Drive::Bumped;
}

void DeadReckoningPlant::arrived(CoverageRover& r) {
  ++teamMoves_;
  if (p_.localisation.loopClosure) lastEntered_[r.cell] = teamMoves_;
  if (of(r).loopDue) closeLoop(r);
  TrueState& s = of(r);
  const double error = s.odo.error().norm();
  RoverTrack& t = recorder_.track(r.id);
  t.truePoints.push_back(truePos(r));
  t.believedPoints.push_back(believedPos(r));
  t.errorM.push_back(static_cast<float>(error));
  s.errorSum += error;
}

void DeadReckoningPlant::closeLoop(CoverageRover& r) {
  DeadReckoning& odo = of(r).odo;
  const Eigen::Vector2d oldError = odo.error();
  const double oldHeading = odo.headingError();
  const Eigen::Vector2d believed = believedPos(r) + odo.closeLoop(p_.localisation.loopClosureKeep);
  const auto cell = localToCell(g_, believed);
  const int i = cell ? g_.index(*cell) : -1;
  KnowledgeMap& m = team_.map(r.mapId);
  if (i < 0 || (i != r.cell && (!m.inRegion(i) || m.state(i) == CellState::Obstacle || !team_.isFree(i)))) {
    odo.undoLoop(oldError, oldHeading);  // waits for the next revisit
    return;
  }
  if (i != r.cell) {
    team_.move(r.id, r.cell, i);
    r.cell = i;
    m.visit(i);
    lastEntered_[i] = teamMoves_;
    recorder_.cellChanged(i, CellState::Visited, m.visits(i));
  }
  odo.setOffset(believed - cellToLocal(g_, *cell));
  ++recorder_.track(r.id).loopClosures;
}

void DeadReckoningPlant::summarise(CoverageResult& res) const {
  CoverageMetrics& mt = res.metrics;
  mt.localisation = true;
  mt.trueVisitedCells = trueVisitedCount_;
  mt.trueCoverage = static_cast<double>(trueVisitedCount_) / mt.freeCells;
  mt.bumps = bumpCount_;
  double errorSum = 0, finalSum = 0;
  std::size_t samples = 0;
  for (std::size_t k = 0; k < state_.size(); ++k) {
    const TrueState& s = state_[k];
    RoverTrack& t = res.rovers[k];
    errorSum += s.errorSum;
    samples += t.errorM.size();
    t.maeM = t.errorM.empty() ? 0.0 : s.errorSum / static_cast<double>(t.errorM.size());
    for (float e : t.errorM) mt.maxErrorM = std::max(mt.maxErrorM, static_cast<double>(e));
    finalSum += s.odo.error().norm();
    mt.loopClosures += t.loopClosures;
  }
  // Paper 000 eq. 6 with the 1/N it omits, N = every move of every rover.
  mt.maeM = samples ? errorSum / static_cast<double>(samples) : 0.0;
  mt.finalErrorM = finalSum / static_cast<double>(state_.size());
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

std::unique_ptr<Plant> makeDeadReckoningPlant(const World& world, const CoverageParams& params,
                                              TeamOccupancy& team, Recorder& recorder,
                                              const std::vector<CoverageRover>& rovers) {
  return std::make_unique<DeadReckoningPlant>(world, params, team, recorder, rovers);
}

}  // namespace rover::coverage
