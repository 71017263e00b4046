#pragma once
// The team mission family as registered planners: "team-search" (paper 001: LHC_GW_CONV route,
// RRT* per rover and segment, simulation, prioritised coordination; SPEC §3) and "hybrid" (SPEC
// §4: the same route, the footprints covered by the myopic planner).
#include <memory>

#include "core/common/params.hpp"
#include "core/planning/planner.hpp"
#include "core/planning/rover_range.hpp"
#include "core/team/team_mission.hpp"

namespace rover::team {

// Everything a team planner takes: the mission parameters plus how often the finished plan is
// replayed to the event sink.
struct TeamPlannerParams {
  TeamMissionParams mission;
  // s of mission time between two pose events of the replay: one second gives a browser ~2300
  // frames for a paper-scale mission (ours).
  double poseInterval = 1.0;
  // What the operator states one rover can do (core/planning/rover_range.hpp); 0 = not stated.
  planning::RoverRange range;
};

const ParamTable<TeamPlannerParams>& teamParamTable();
// Defaults overridden by `values`, then TeamMissionParams::validate(). Throws with the key.
TeamPlannerParams parseTeamParams(const ParamSet& values);

std::unique_ptr<Planner> makeTeamSearchPlanner();
std::unique_ptr<Planner> makeHybridPlanner();

// The planner-neutral view of a team mission (metric keys as in `roverplan mission --json`).
PlanResult toPlanResult(const TeamMissionResult& r, const TeamPlannerParams& p, bool hybrid,
                        double planWallSeconds);

}  // namespace rover::team
