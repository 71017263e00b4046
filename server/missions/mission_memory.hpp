#pragma once
// What a mission costs in memory, estimated before it is queued (issue 14: "per-mission memory
// counted against a budget before queueing"), as an upper bound of its peak (issue 22: "budgets
// that are true"). Each planner gives its own estimate (Planner::memoryEstimate, next to the code
// that holds the memory: core/coverage/coverage_memory.hpp, core/team/team_memory.hpp); the
// server holds the budget it is counted against.
#include <cstdint>
#include <string>

#include "core/planning/planner_specs.hpp"

namespace rover::missions {

using MemoryEstimate = rover::MemoryEstimate;

// The default mission memory budget: half the machine's physical memory (4 GiB if unknown).
std::uint64_t defaultMissionMemoryBudget();

// Sets the C heap so what a finished mission freed goes back to the system (issue 22: "memory
// returned after a mission"), once per process; the mission manager calls it. See the source.
void returnFreedMemoryPromptly();

// "1.5 GiB" / "230 MiB" for messages.
std::string formatBytes(std::uint64_t bytes);

}  // namespace rover::missions
