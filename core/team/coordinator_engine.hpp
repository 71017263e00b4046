#pragma once
// The prioritised coordinator of paper 001 fig. 8 (coordinator.hpp's coordinateWith) as a class,
// shared by the files that implement it: coordinator_run.cpp (set-up, tries, the traffic checks),
// coordinator_legs.cpp (one leg: its pieces, waits and re-plans), coordinator_stops.cpp (where a
// rover may stop: parking, stepping aside, cutting a trajectory back). Internal to core/team.
// Choices made here where the paper is silent are listed in coordination.hpp.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/common/random.hpp"
#include "core/team/coordinator.hpp"
#include "core/team/plan_ahead.hpp"
#include "core/team/separation.hpp"

namespace rover::team::detail {

inline Eigen::Vector2d xyOf(const TrajectorySample& s) { return {s.x, s.y}; }

inline std::string oneDecimal(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

inline std::uint64_t seedFor(std::uint64_t seed, int rover, int leg, int piece, int attempt) {
  std::uint64_t s = deriveSeed(seed, static_cast<std::uint64_t>(rover));
  s = deriveSeed(s, static_cast<std::uint64_t>(leg));
  s = deriveSeed(s, static_cast<std::uint64_t>(piece));
  return deriveSeed(s, static_cast<std::uint64_t>(attempt));
}

inline Eigen::Vector2d legGoal(const Leg& leg) { return leg.via.empty() ? leg.goal : leg.via.back(); }

class Coordinator {
 public:
  Coordinator(const std::vector<RoverTask>& tasks, std::vector<int> order, int firstRound, const LegPlanner& planner,
              const LegSimulator& simulator, const ConflictPolicy& policy,
              const CoordinationParams& params, std::uint64_t seed,
              CoordinationObserver* observer, const CancelToken* cancel)
      : tasks_(tasks),
        order_(std::move(order)),
        firstRound_(firstRound),
        planner_(planner),
        simulator_(simulator),
        policy_(policy),
        p_(params),
        seed_(seed),
        observer_(observer),
        cancel_(cancel),
        period_(params.controller.samplePeriod),
        traffic_(params.safetyDistance, params.controller.samplePeriod) {}

  CoordinationResult run();

 private:
  enum class Outcome { Accepted, Skipped, NoPath, InvalidGoal, Steep, TiltsAtStart, KeepOut, Cancelled };

  struct Candidate {
    std::vector<Eigen::Vector2d> path;         // waypoints, the rover's position first
    std::vector<TrajectorySample> samples;     // new samples (waits, then driving)
    bool reached = false;                      // the simulation entered the last waypoint's circle
  };


  bool cancelled() const { return cancel_ && cancel_->cancelled(); }
  const TrajectorySample& last(int k) const { return out_.trajectories[k].samples.back(); }
  Eigen::Vector2d here(int k) const { return xyOf(last(k)); }
  std::uint64_t slipSeed(std::uint64_t salt, int k, int i, int piece, int attempt) const;

  // The first sample: the rover at rest on its start (a drive with the start as its only
  // waypoint records exactly that, with the terrain height and attitude).
  void startRover(int k);

  // Every planned leg from its nominal start, planned ahead on the threads the caller granted
  // while the rovers are coordinated (plan_ahead.hpp). A via leg (hybrid) whose fixed points a
  // rover may drive is not planned; one that it may not is planned ahead too.
  void planAhead();

  // The keep-out zones round the starts of the rovers planned after k (policy_.standingKeepOut()),
  // which stand there for the whole of k's plan: every plan of a leg of k from `from` to `goal`
  // stays out of them from its first try. A zone holding `from` or `goal` is left out, as
  // keepOutOf leaves out a conflict's (the coordinator's own checks still keep the rovers apart).
  std::vector<KeepOutZone> standingZones(int k, const Eigen::Vector2d& from, const Eigen::Vector2d& goal) const;

  // Every straight move of a via leg's fixed points, from `from`, is one the rover may drive.
  bool viaValid(const Eigen::Vector2d& from, const Leg& leg) const;

  // The path of one try: the fixed points of a via leg (first try, if every edge is valid), the
  // path planned ahead (first try, if the rover stopped where that plan started), else a plan now.
  PathResult tryPath(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                     const std::vector<KeepOutZone>& keepOut);

  PlanAhead::Request replan(int k, int i, int piece, int attempt, const Eigen::Vector2d& goal,
                            const std::vector<KeepOutZone>& keepOut) const;

  // Rover k standing where it is for `ticks` samples, appended to `samples`.
  void stand(int k, int ticks, std::vector<TrajectorySample>& samples) const;

  // The rover stands `waitTicks` samples, then drives `path`.
  Candidate simulateTry(int k, const std::vector<Eigen::Vector2d>& path, int waitTicks,
                        std::uint64_t seed);

  // `c` started `ticks` samples later: the rover stands where it is meanwhile. The terrain does
  // not change, so the simulated motion is the same, only later.
  Candidate delayed(int k, const Candidate& c, int ticks) const;

  // `stand` for firstConflict: standing for as long as any higher-priority rover moves.
  static constexpr long kForGood = -1;
  long dwellTicks() const { return std::lround(policy_.dwell() / period_); }

  // The first conflict with a higher-priority rover (the traffic table holds exactly those) of
  // rover k standing where it is for `ticks` samples, then driving `samples` (appended to its
  // trajectory after them); then standing at its last position for `stand` samples, or, with
  // kForGood, for as long as any higher-priority rover moves.
  std::optional<Conflict> firstConflict(int k, std::span<const TrajectorySample> samples, int ticks,
                                        long stand) const;

  // The delays at which runPiece starts a try: the policy's; for a rover the departure order
  // holds back (not in its first round: its way out opens only once rovers round it have left)
  // that has not left its start yet, when the policy recovers (timed), more, every wait_step up
  // to one past the end of the traffic table, when every rover planned so far stands where it
  // stays. Such a rover may stand at its start as long as it likes: every rover planned before it
  // kept the safety distance from it standing there for the whole mission. So a rover inside a
  // formation waits until the rovers that left before it have driven off (issue 25: with 64
  // rovers the last of a 2 × 2 block met team mates driving out past it at every delay up to
  // max_waits × wait_step and skipped all its 5 legs without moving). Rovers free to leave at
  // once keep the policy's delays.
  std::vector<int> startDelays(int k) const;
  // Start delays for rover k after `after` ticks, one wait step apart, until the traffic table
  // ends: a rover that waits that long meets no team mate still moving.
  std::vector<int> delaysUntilTrafficEnds(int k, int after) const;

  // The steepest |roll| or |pitch| of a try (rad) and which of the two it was: what a leg's note
  // reports beside the attitude check it was refused against (issue 27: a note that named "the
  // attitude limit" while the operator's attitude_limit was 45° and the try tilted 15.0°).
  struct Tilt {
    double angle = 0;
    bool pitch = false;
  };
  static Tilt steepestTilt(const std::vector<TrajectorySample>& samples);
  std::string tiltNote(const char* what, const Tilt& reached, const char* reachedBy = "the least tilted try") const;

  // The first sample with |roll| or |pitch| above the attitude check, if any.
  std::optional<Eigen::Vector2d> firstExceedance(const std::vector<TrajectorySample>& samples) const;

  // The first sample on a keep-out zone's cell, if any: such a try is never committed (the
  // planned path keeps out, but the simulated rover cuts corners and slips).
  std::optional<Eigen::Vector2d> firstForbidden(const std::vector<TrajectorySample>& samples) const;

  void commit(int k, const Candidate& c);

  bool reachesGoal(const Candidate& c, const Eigen::Vector2d& goal) const;

  // Keeps later tries out of `zone`, unless that would wall in the start or the goal (then only
  // the seed changes).
  void keepOutOf(int k, const Eigen::Vector2d& goal, const KeepOutZone& zone,
                 std::vector<KeepOutZone>& keepOut) const;

  std::string conflictNote(const Conflict& c) const;

  // One piece of a leg, the same loop for every policy: tries with new seeds, each keeping out
  // of where the earlier ones came too close or tilted; each within-limit try started at the
  // policy's delays; then the policy's waits; then the caller skips the leg.
  Outcome runPiece(int k, int i, int piece, const Eigen::Vector2d& goal, LegRecord& rec,
                   bool& reachedGoal);

  // The rover stays where its last leg left it for the rest of the mission. If a higher-priority
  // rover still moving would pass too close, it drives out of the way (ours).
  // It also drives off when it stands near a goal or fixed point of a lower-priority rover's
  // leg: parked there for good, it would block that leg for ever (hybrid missions on the default
  // map: 14 of 18 skipped legs were the team mates' last coverage moves round the first rover's
  // end).
  void park(int k);

  // Every committed sample of rover k was checked against the traffic table, but the rest of the
  // mission after its last one only as far as the policy checks it: a leg for the dwell, then
  // park() — which finds no spot near a map edge or a wall, or runs out of moves (issue 25: a
  // rover parked at the east edge of the Gale patch, run over four times by two higher-priority
  // rovers that came by later). The rover then stops at the latest end of a committed move where
  // it may stand for the rest of the mission — its start at worst, where every rover planned
  // earlier kept clear of it — and the moves after it are undone: their legs end there, short or
  // skipped for the conflict. So a finished rover never stands in a planned rover's way, by
  // construction. (The observer was told of the undone pieces as they came; the result is
  // final.)
  void stopWhereSafe(int k);

  // Cuts rover k back to its stop `stop` (stopWhereSafe): the legs after it end there, short or
  // skipped for `conflict`; the moves aside after it are dropped. Keeps the leg records as they
  // were in legsBefore_, to undo a cut.
  void cutAt(int k, std::size_t stop, const Conflict& conflict);


  // Drives rover k to a spot it can reach and stand at without a conflict, clear of later rovers'
  // goals, and commits the move; returns when it started (nullopt: no spot works). Candidates:
  // back along its own trajectory (ground it has driven, so reachable even in a dead end), every
  // 2 m, then rings of growing radius round it; within the attitude limit if at all possible (a
  // collision is worse than a tilt, so a second pass accepts a move that exceeds it, reported as
  // an exceedance). `move` numbers the calls for a rover (it salts the seeds).
  // Where it looks and how hard: the policy's AsideSearch (paper: 40 m back, 7 rings of 8, an
  // RRT* call per spot, a spot clear for good; timed: 200 m back, 9 rings of 16, the traffic
  // table read first).
  std::optional<double> moveAside(int k, int move);

  // Rover k tilts when it turns in place where it stands (a stop on ground steeper than the limit
  // in some direction): drives straight out, nearest its heading first (every 10° round), 0.5 to
  // 1.5 m, to ground where it may stop and turn, without tilting, entering a zone or a conflict
  // (delayed like any try). The planner's edge check is not asked: its limit is the planning
  // one (14°), and the rover stands on steeper ground already; the simulated drive is the judge.
  // Commits the move; false when no heading works.
  bool escapeTurn(int k, int i, int salt);

  // `p` is closer than the safety distance plus both acceptance circles to a goal or fixed point
  // of a lower-priority rover's leg (the spacing the task builder keeps between goals).
  bool blocksLaterGoal(int k, const Eigen::Vector2d& p) const;

  void runLeg(int k, int i);

  const std::vector<RoverTask>& tasks_;
  const std::vector<int> order_;  // the order the rovers are planned in (departureOrder)
  const int firstRound_;          // how many of order_ leave in its first round
  std::vector<int> rank_;         // per rover, its place in order_
  const LegPlanner& planner_;
  const LegSimulator& simulator_;
  const ConflictPolicy& policy_;
  const CoordinationParams& p_;
  const std::uint64_t seed_;
  CoordinationObserver* observer_;
  const CancelToken* cancel_;
  const double period_;
  std::unique_ptr<PlanAhead> ahead_;
  std::vector<std::size_t> firstJob_;  // per rover, the index of its first leg's job
  // Per rover, the samples and waypoints it had after each committed move (its start first):
  // where stopWhereSafe may cut it.
  struct Stop {
    std::size_t samples = 0, path = 0;
  };
  std::vector<std::vector<Stop>> stops_;
  std::vector<LegRecord> legsBefore_;  // cutAt: the leg records before the last cut
  CoordinationResult out_;
  TrafficTable traffic_;
  // The last piece was skipped for a conflict in its first second: no try nor delay got the
  // rover away from where it stands (runPiece sets it, runLeg reads it).
  bool boxedIn_ = false;  // the rovers done so far; the others standing at their starts
  int legsDone_ = 0;
  int legsTotal_ = 0;
};

}  // namespace rover::team::detail
