#pragma once
// The coordinator stage (paper 001 fig. 8, SPEC §3.4): rovers in priority order, each leg planned
// by a LegPlanner, driven by a LegSimulator from where the rover really stopped, and checked
// sample by sample in time against every higher-priority rover's committed trajectory. What it
// does with a try that comes too close is the ConflictPolicy (PaperPolicy, TimedPolicy); the
// loop is the same for every policy. Rovers boxed in at their starts by others are planned after
// them (planning/departure.hpp); every rover stands at its start until it is planned. Takes no
// terrain: tests drive it with a fake planner and a fake rover.
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/planning/departure.hpp"
#include "core/team/coordination.hpp"
#include "core/team/leg_planner.hpp"
#include "core/team/leg_simulator.hpp"

namespace rover::team {

// Where a stopped rover looks for a spot to step aside to (park() and the recoveries,
// coordinator.cpp moveAside), and how hard: constants each policy owns. Spots: back along its own
// trajectory (ground it has driven, so reachable even in a dead end) every 2 m up to `backAlong`,
// then rings of 1.5, 2.5, 3.5, 5, 7, 10, 14, 20, 28 m up to `maxRing`, `directions` spots each.
struct AsideSearch {
  int parkingMoves = 1;      // moves at the end of the mission before the rover stays put
  int recoveriesPerLeg = 0;  // moves out of a skipped leg's way or out of a turn that tilts
  double backAlong = 40.0;   // m
  double maxRing = 14.0;     // m
  int directions = 8;
  // true: how long each spot stays clear is read off the traffic table before any path is
  // planned; spots clear for good first, else (nearest first) one clear for at least `minHold`; a
  // straight move before RRT*, which gets at most `rrtCalls` calls, and at most `simulations`
  // simulated moves; the rover must be able to turn where it stops. false: an RRT* call per spot
  // and a spot clear for good.
  bool readsTraffic = false;
  double minHold = 20.0;  // s
  int rrtCalls = 8;
  int simulations = 48;
};

// How a piece of a leg answers a try that comes closer than the safety distance to a
// higher-priority rover (or tilts past the attitude check): the rules the coordinator's loop asks.
// Each try is simulated once; then the rules below decide. PaperPolicy and TimedPolicy own their
// constants; .decisions/0002 gives each timed rule's evidence.
class ConflictPolicy {
 public:
  virtual ~ConflictPolicy() = default;
  virtual const char* name() const = 0;
  // Delays, in samples, at which the simulated try is started (the rover standing meanwhile) and
  // checked again before the leg is re-planned with a keep-out zone: 0 first, then ascending
  // (coordinateWith checks). {0}: re-plan at once.
  virtual const std::vector<int>& startDelays() const = 0;
  // A try that tilts past the attitude check is still checked for conflicts: a conflict, if any,
  // places the keep-out zone and may end the re-plans. false: it is re-planned at once, keeping
  // half a metre out of the spot where it tilted.
  virtual bool checksTiltedTries() const = 0;
  // A conflict within the first second of a try ends the re-plans (no other path can dodge it).
  virtual bool earlyConflictEndsReplans() const = 0;
  // Two tries in a row with the same keep-out zones whose plans end short of a goal the planner
  // proved cut off (PathResult::goalCutOff) end the re-plans: a new seed only moves where the
  // tree stops.
  virtual bool repeatedShortEndsReplans() const = 0;
  // This many tries in a row that reach the goal and, started at once, meet a higher-priority
  // rover only while standing there, where no keep-out zone can go (it would wall in the start or
  // the goal), end the re-plans; 0 = never. Such a try is the same problem again with a new seed,
  // and no path dodges a rover that comes by the goal while this one dwells there. Any other try
  // breaks the run.
  virtual int unzonedConflictsEndReplans() const = 0;
  // After the re-plans, the first try within the attitude check is tried again this many times,
  // each time one wait step later and simulated anew; then the leg is skipped.
  virtual int waitsAfterReplans() const = 0;
  // An invalid goal ends the piece at the first try that finds it (no keep-out zone can make it
  // valid); false: the re-plans stop and the waits still run for an earlier try.
  virtual bool invalidGoalEndsPiece() const = 0;
  // s the rover is checked standing at the end of a leg (of every leg but its last when
  // lastLegParks).
  virtual double dwell() const = 0;
  // The try of a rover's last leg is checked standing at its goal for as long as any
  // higher-priority rover moves: it parks there. false: for the dwell, like every other leg, and
  // park() moves the rover aside before each later pass (needs recovers; coordinateWith checks).
  virtual bool lastLegParks() const = 0;
  // Recoveries (ours), for a rover that would otherwise stay stuck where it stands:
  // - a try that would end where the rover cannot stop and turn (canStop) is refused like a
  //   tilted one;
  // - a try that tilts while the rover turns in place at its start first drives straight out,
  //   nearest its heading first (every 10° round), to ground where it may turn;
  // - a leg skipped for conflicts, where standing still would be run over by a higher-priority
  //   rover later, first steps aside (a spot clear for good, else the nearest clear for a while),
  //   then tries the leg again;
  // - parking at the end moves again until the rover is clear for good.
  // How many such moves and where they look: aside().
  virtual bool recovers() const = 0;
  virtual const AsideSearch& aside() const = 0;
  // The radius of the keep-out zone round the start of every rover planned after this one (which
  // stands there, in the traffic table, for the whole mission while this one is planned), given
  // to every plan of this rover from its first try; 0 = none, the conflicts place the zones.
  virtual double standingKeepOut() const = 0;
};

// Paper 001 fig. 8 as SPEC §3.4 reads it: re-plan with a new seed (and a keep-out zone) on each
// conflict, then wait whole wait steps (max_waits), then skip; dwell_check at each leg's end; the
// last leg parks for good; one move aside at the end, to a spot clear for good.
class PaperPolicy : public ConflictPolicy {
 public:
  explicit PaperPolicy(const CoordinationParams& p);
  const char* name() const override { return "paper"; }
  const std::vector<int>& startDelays() const override { return delays_; }
  bool checksTiltedTries() const override { return true; }
  bool earlyConflictEndsReplans() const override { return true; }
  bool repeatedShortEndsReplans() const override { return false; }
  int unzonedConflictsEndReplans() const override { return 0; }
  int waitsAfterReplans() const override { return waits_; }
  bool invalidGoalEndsPiece() const override { return false; }
  double dwell() const override { return dwell_; }
  bool lastLegParks() const override { return true; }
  bool recovers() const override { return false; }
  const AsideSearch& aside() const override { return aside_; }
  double standingKeepOut() const override { return 0.0; }

 private:
  std::vector<int> delays_{0};
  int waits_;
  double dwell_;
  AsideSearch aside_;  // the defaults: the paper mode's one move aside
};

// Ours: start the same try later (0, δ, 2δ, … up to max_waits × wait_step, δ = delay_step) — a
// reservation check in time against every committed trajectory — and re-plan only when no delay
// clears it; the stop rules and the recoveries above. The dwell is dwell_check, the time a stopped
// rover has to step aside when its next leg finds no clear try (.decisions/0002).
class TimedPolicy : public ConflictPolicy {
 public:
  // The two stop rules, on by default; off only to measure what each one does (tests, 0002).
  struct StopRules {
    bool repeatedShortEndsReplans = true;
    int unzonedConflictsEndReplans = 3;
  };
  explicit TimedPolicy(const CoordinationParams& p) : TimedPolicy(p, StopRules{}) {}
  TimedPolicy(const CoordinationParams& p, StopRules rules);
  const char* name() const override { return "timed"; }
  const std::vector<int>& startDelays() const override { return delays_; }
  bool checksTiltedTries() const override { return false; }
  bool earlyConflictEndsReplans() const override { return false; }
  bool repeatedShortEndsReplans() const override { return rules_.repeatedShortEndsReplans; }
  int unzonedConflictsEndReplans() const override { return rules_.unzonedConflictsEndReplans; }
  int waitsAfterReplans() const override { return 0; }
  bool invalidGoalEndsPiece() const override { return true; }
  double dwell() const override { return dwell_; }
  bool lastLegParks() const override { return false; }
  bool recovers() const override { return true; }
  const AsideSearch& aside() const override { return aside_; }
  double standingKeepOut() const override { return standing_; }

 private:
  std::vector<int> delays_;
  StopRules rules_;
  double dwell_;
  double standing_;
  AsideSearch aside_;
};

// Plans, simulates and coordinates the team with the given stages. `params` gives the limits
// (safety distance, re-plans, waits, pieces, attitude check, keep-out radius, threads, the
// controller's sample period and acceptance radius); `seed` drives every planning call
// (deriveSeed per rover, leg, piece and attempt) and the slip seeds, so the result is the same for
// a seed whatever the thread count. `planner` must be safe to call from several threads.
// Throws InvalidInput naming rovers[k] when the simulator cannot place a start. The rovers are
// planned in `departure`, planning::departureOrder of the tasks' starts (null: over open ground;
// coordinate() gives it over the lattice's ground, traversal_lattice.hpp departureOverGround);
// InvalidInput naming the first boxed-in rover when it leaves one boxed in, InvalidParameter
// when it does not hold every rover once.
CoordinationResult coordinateWith(const std::vector<RoverTask>& tasks, const LegPlanner& planner,
                                  const LegSimulator& simulator, const ConflictPolicy& policy,
                                  const CoordinationParams& params, std::uint64_t seed,
                                  CoordinationObserver* observer = nullptr,
                                  const CancelToken* cancel = nullptr,
                                  const planning::Departure* departure = nullptr);

}  // namespace rover::team
