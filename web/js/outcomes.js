// How runs end and what they report, as the server names them: a mission's or study's status
// (server/store/run_status.hpp), a plan's stop reason, incident kinds and target statuses
// (core/planning/outcomes.hpp). The server's tables are the source (OpenAPI publishes them as
// enums); tests/server/test_outcome_names.cpp checks these lists against them, in order.

export const RunStatus = Object.freeze({
  Queued: 'queued',
  Running: 'running',
  Succeeded: 'succeeded',
  CompletedWithWarnings: 'completed_with_warnings',
  Failed: 'failed',
  Cancelled: 'cancelled',
  Interrupted: 'interrupted',
});

export const StopReason = Object.freeze({
  GoalReached: 'goal_reached',
  NothingLeft: 'nothing_left',
  StepBudget: 'step_budget',
  MissionComplete: 'mission_complete',
  Cancelled: 'cancelled',
});

export const IncidentKind = Object.freeze({
  Collision: 'collision',
  Exceedance: 'exceedance',
  Short: 'short',
  Skipped: 'skipped',
  NoSlot: 'no_slot',
  Bump: 'bump',
});

export const TargetStatus = Object.freeze({
  Reached: 'reached',
  Short: 'short',
  Skipped: 'skipped',
  Unreachable: 'unreachable',
});

const RUN_STATUSES = Object.values(RunStatus);

// A status the server reports (not the page's own 'cancelling' or '').
export const isRunStatus = (s) => RUN_STATUSES.includes(s);

// Still to run or running: it may be cancelled and its stream still moves.
export const isActive = (s) => s === RunStatus.Queued || s === RunStatus.Running;

// A status the run does not leave (the server's isFinal).
export const isFinal = (s) => isRunStatus(s) && !isActive(s);

// Ran to its end: cleanly, or with warnings (short/skipped legs, unreachable ground…).
export const isCompleted = (s) => s === RunStatus.Succeeded || s === RunStatus.CompletedWithWarnings;

// Ended without its result: failed, cancelled or interrupted.
export const isStopped = (s) => isFinal(s) && !isCompleted(s);

// A status in words, for badges: "completed with warnings".
export const statusText = (s) => String(s || '').replace(/_/g, ' ');
