#pragma once
// How a plan ended and what it reports, as types: why a planner stopped, the kinds of incident it
// tells the user about and what became of a team route's targets. Their names (the JSON and the
// study database carry them) are the tables below, the only place they are written.
#include <array>

#include "core/common/enum_names.hpp"

namespace rover {

// Why a planner stopped (PlanResult::stopReason).
enum class StopReason {
  GoalReached,      // coverage goal met (for Voronoi: by every rover in its region)
  NothingLeft,      // frontier mode: no reachable unexplored cell remains; under localisation
                    // error also: every rover's own map walls it in
  StepBudget,       // max_steps ran out first
  MissionComplete,  // team planners: every leg was planned (reached or not: see the targets)
  Cancelled,
};

template <>
struct EnumNames<StopReason> {
  static constexpr std::array<EnumName<StopReason>, 5> table{{
      {StopReason::GoalReached, "goal_reached"},
      {StopReason::NothingLeft, "nothing_left"},
      {StopReason::StepBudget, "step_budget"},
      {StopReason::MissionComplete, "mission_complete"},
      {StopReason::Cancelled, "cancelled"},
  }};
};

// Something the user must be told about (Incident::kind).
enum class IncidentKind {
  Collision,   // two rovers closer than the safety distance in the returned plan
  Exceedance,  // |roll| or |pitch| over the attitude limit for a run of samples
  Short,       // a rover's leg ended away from its goal
  Skipped,     // a rover's leg was given up
  NoSlot,      // no valid ground for the rover's slot at a route target
  Bump,        // coverage under localisation error: a move into an obstacle its map held free
};

template <>
struct EnumNames<IncidentKind> {
  static constexpr std::array<EnumName<IncidentKind>, 6> table{{
      {IncidentKind::Collision, "collision"},
      {IncidentKind::Exceedance, "exceedance"},
      {IncidentKind::Short, "short"},
      {IncidentKind::Skipped, "skipped"},
      {IncidentKind::NoSlot, "no_slot"},
      {IncidentKind::Bump, "bump"},
  }};
};

// What became of a team route's target (RouteTarget::status), from its legs (one per rover).
enum class TargetStatus {
  Reached,      // every rover's leg reached its slot
  Short,        // some legs ended away from it
  Skipped,      // no leg got there or near
  Unreachable,  // no rover got a slot on valid ground
};

template <>
struct EnumNames<TargetStatus> {
  static constexpr std::array<EnumName<TargetStatus>, 4> table{{
      {TargetStatus::Reached, "reached"},
      {TargetStatus::Short, "short"},
      {TargetStatus::Skipped, "skipped"},
      {TargetStatus::Unreachable, "unreachable"},
  }};
};

}  // namespace rover
