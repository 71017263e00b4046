#pragma once
// The coordinator stage (paper 001 fig. 8, SPEC §3.4): rovers in priority order, each leg planned
// by a LegPlanner, driven by a LegSimulator from where the rover really stopped, and checked
// sample by sample in time against every higher-priority rover's committed trajectory. What it
// does with a try that comes too close is the ConflictPolicy; the loop is the same for every
// policy. Takes no terrain: tests drive it with a fake planner and a fake rover.
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/team/coordination.hpp"
#include "core/team/leg_planner.hpp"
#include "core/team/leg_simulator.hpp"

namespace rover::team {

// How a piece of a leg answers a try that comes closer than the safety distance to a
// higher-priority rover (or tilts past the attitude check). Each try is simulated once; then:
struct ConflictPolicy {
  // Delays, in samples, at which the simulated try is started (the rover standing meanwhile) and
  // checked again before the leg is re-planned with a keep-out zone. {0}: re-plan at once.
  std::vector<int> startDelays{0};
  // A try that tilts past the attitude check is still checked for conflicts: a conflict, if any,
  // places the keep-out zone and may end the re-plans. false: it is re-planned at once, keeping
  // half a metre out of the spot where it tilted.
  bool checkTiltedTries = false;
  // A conflict within the first second of a try ends the re-plans (no other path can dodge it).
  bool earlyConflictEndsReplans = false;
  // Two tries in a row with the same keep-out zones whose plans end short of a goal the planner
  // proved cut off (PathResult::goalCutOff) end the re-plans: a new seed only moves where the
  // tree stops (figures: .decisions/0002).
  bool repeatedShortEndsReplans = false;
  // This many tries in a row that reach the goal and, started at once, meet a higher-priority
  // rover only while standing there, where no keep-out zone can go (it would wall in the start or
  // the goal), end the re-plans; 0 = never. Such a try is the same problem again with a new seed,
  // and no path dodges a rover that comes by the goal while this one dwells there
  // (.decisions/0002). Any other try breaks the run.
  int unzonedConflictsEndReplans = 0;
  // After the re-plans, the first try within the attitude check is tried again this many times,
  // each time one wait step later and simulated anew; then the leg is skipped.
  int waitsAfterReplans = 0;
  // An invalid goal ends the piece at the first try that finds it (no keep-out zone can make it
  // valid); false: the re-plans stop and the waits still run for an earlier try.
  bool invalidGoalEndsPiece = false;
  // s the rover is checked standing at the end of a leg (of every leg but its last when
  // lastLegParks).
  double dwell = 10.0;
  // The try of a rover's last leg is checked standing at its goal for as long as any
  // higher-priority rover moves: it parks there. false: for the dwell, like every other leg, and
  // park() moves the rover aside before each later pass (needs recover; coordinateWith checks).
  // Checked for good, a leg whose goal a higher-priority rover passes much later fails every try
  // and every re-plan (.decisions/0002).
  bool lastLegParks = true;
  // Recoveries (ours), for a rover that would otherwise stay stuck where it stands:
  // - a try that would end where the rover cannot stop and turn (canStop) is refused like a
  //   tilted one;
  // - a try that tilts while the rover turns in place at its start first drives straight out,
  //   nearest its heading first (every 10° round), to ground where it may turn;
  // - a leg skipped for conflicts, where standing still would be run over by a higher-priority
  //   rover later, first steps aside (a spot clear for good, else the nearest clear for 20 s),
  //   then tries the leg again; at most two recoveries per leg;
  // - parking at the end moves again until the rover is clear for good (at most 8 moves).
  // Without them a rover stuck on a steep spot ends many legs short, and one left standing in
  // another's way collides (.decisions/0002).
  bool recover = false;
};

// Paper 001 fig. 8 as SPEC §3.4 reads it: re-plan with a new seed (and a keep-out zone) on each
// conflict, then wait whole wait steps, then skip; dwell_check at each leg's end.
ConflictPolicy paperPolicy(const CoordinationParams& p);
// Ours: start the same try later (0, δ, 2δ, … up to max_waits × wait_step, δ = delay_step) — a
// reservation check in time against every committed trajectory — and re-plan only when no delay
// clears it; then the recoveries above. The dwell is dwell_check, the time a stopped rover has
// to step aside when its next leg finds no clear try.
ConflictPolicy timedPolicy(const CoordinationParams& p);

// Plans, simulates and coordinates the team with the given stages. `params` gives the limits
// (safety distance, re-plans, waits, pieces, attitude check, keep-out radius, threads, the
// controller's sample period and acceptance radius); `seed` drives every planning call
// (deriveSeed per rover, leg, piece and attempt) and the slip seeds, so the result is the same for
// a seed whatever the thread count. `planner` must be safe to call from several threads.
// Throws InvalidInput naming rovers[k] when the simulator cannot place a start.
CoordinationResult coordinateWith(const std::vector<RoverTask>& tasks, const LegPlanner& planner,
                                  const LegSimulator& simulator, const ConflictPolicy& policy,
                                  const CoordinationParams& params, std::uint64_t seed,
                                  CoordinationObserver* observer = nullptr,
                                  const CancelToken* cancel = nullptr);

}  // namespace rover::team
