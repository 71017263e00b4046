#include "core/coverage/coverage_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <memory>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/coverage/coverage_rover.hpp"
#include "core/coverage/move_policy.hpp"
#include "core/coverage/plant.hpp"
#include "core/coverage/recorder.hpp"
#include "core/coverage/team_occupancy.hpp"
#include "core/grid/direction.hpp"
#include "core/grid/neighbours.hpp"

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

const World& validated(const World& world) {
  validateWorld(world);
  return world;
}
const CoverageParams& validated(const CoverageParams& params) {
  validateCoverageParams(params);
  return params;
}

// The coverage engine after Fields2Cover's stages: the move policy picks, the plant drives and
// senses, the team occupancy says who is where, the recorder keeps what happened; this loop only
// orders them (SPEC §1: sense, choose, move, until the stop rule). .decisions/0001.
class Engine {
 public:
  Engine(const World& world, const std::vector<StartCell>& starts, const CoverageParams& params,
         EventSink* sink, const CancelToken* cancel)
      : world_(validated(world)),
        p_(validated(params)),
        cancel_(cancel),
        team_(world, starts, params.mode),
        recorder_(world, p_, sink, starts),
        policy_(world, p_, team_) {
    for (std::size_t k = 0; k < starts.size(); ++k) {
      CoverageRover r;
      r.id = static_cast<int>(k);
      r.cell = starts[k].cell;
      r.heading = starts[k].heading;
      r.mapId = team_.mapIdOf(r.id);
      rovers_.push_back(std::move(r));
    }
    plant_ = makePlant(world, p_, team_, recorder_, rovers_);
    for (auto& r : rovers_) {
      team_.map(r.mapId).visit(r.cell);
      recorder_.cellChanged(r.cell, CellState::Visited, 1);
      plant_->sense(r);
    }
  }

  CoverageResult run();

 private:
  // Voronoi rovers stop one by one at their region's goal; an overlap team stops together.
  void checkRegionGoal(CoverageRover& r) {
    if (team_.regionsApart() && !r.done && team_.map(r.mapId).goalReached(p_.coverage)) {
      r.done = true;
      r.doneReason = StopReason::GoalReached;
    }
  }
  // The recorder's curve point; a true pose's truly visited cells are the maps' visited cells.
  void stepEnded(std::int64_t step) {
    const int visited = team_.visitedTotal();
    recorder_.stepEnded(step, moves_, visited, plant_->poseIsTrue() ? visited : plant_->trueVisited(), team_,
                        *plant_, rovers_);
  }
  enum class Turn { Next, TeamGoal };
  // One rover's turn in a step.
  Turn play(CoverageRover& r, std::int64_t step);

  const World& world_;
  const CoverageParams p_;
  const CancelToken* cancel_;
  TeamOccupancy team_;
  Recorder recorder_;
  MovePolicy policy_;
  std::vector<CoverageRover> rovers_;
  std::unique_ptr<Plant> plant_;
  std::int64_t moves_ = 0;
};

Engine::Turn Engine::play(CoverageRover& r, std::int64_t step) {
  const int next = policy_.choose(r);
  if (r.done) return Turn::Next;
  if (next < 0) {
    if (plant_->stopsWalledIn() && policy_.walledIn(r)) {
      // Under localisation error the map itself can wall a rover in (bumps and smeared
      // obstacles all round): it can never move again, so it stops.
      r.done = true;
      r.doneReason = StopReason::NothingLeft;
      return Turn::Next;
    }
    recorder_.waited(r.id);  // boxed in by team mates this step
    return Turn::Next;
  }
  const bool wasCircling = r.circling;
  const int dir = neighbourDir(world_.geometry(), r.cell, next);
  Motion motion;
  if (const Drive drive = plant_->drive(r, next, dir, step, motion); drive != Drive::Moved) {
    // Not moved: a team mate truly in the way, or a bump (the map changed: the goal, which
    // counts known obstacles, may now be met).
    if (drive == Drive::Blocked) recorder_.waited(r.id);
    checkRegionGoal(r);
    return team_.teamGoalReached(p_.coverage) ? Turn::TeamGoal : Turn::Next;
  }
  KnowledgeMap& m = team_.map(r.mapId);
  const bool revisit = m.visit(next);
  recorder_.moved(r.id, next, r.heading, dir, motion.horizontal, motion.dh, revisit);
  recorder_.cellChanged(next, CellState::Visited, m.visits(next));
  team_.move(r.id, r.cell, next);
  r.cell = next;
  r.heading = dir;
  plant_->arrived(r);
  if (wasCircling && r.circling) {
    if (const int from = policy_.afterContourMove(r); from >= 0) recorder_.turned(r.id, from, r.heading);
  }
  ++moves_;
  plant_->sense(r);
  checkRegionGoal(r);
  return team_.teamGoalReached(p_.coverage) ? Turn::TeamGoal : Turn::Next;
}

CoverageResult Engine::run() {
  const std::int64_t budget = p_.stepBudget(world_.geometry().cellCount());
  std::int64_t step = 0;
  for (auto& r : rovers_) checkRegionGoal(r);
  bool goal = team_.teamGoalReached(p_.coverage);
  stepEnded(0);

  StopReason stop = StopReason::StepBudget;
  while (true) {
    const bool allDone = std::all_of(rovers_.begin(), rovers_.end(), [](auto& r) { return r.done; });
    if (goal || allDone) {
      const bool anyNothingLeft = std::any_of(rovers_.begin(), rovers_.end(), [](auto& r) {
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
      if (play(r, step) == Turn::TeamGoal) {
        goal = true;
        break;
      }
    }
    stepEnded(step);
  }
  return recorder_.finish(stop, step, team_, *plant_);
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
