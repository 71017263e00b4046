#pragma once
// Cooperative cancellation: the owner (mission manager, CLI signal handler) sets it, a planner
// checks it once per step and returns with status Cancelled. Same idea as OMPL's
// PlannerTerminationCondition, reduced to one flag.
#include <atomic>

namespace rover {

class CancelToken {
 public:
  void cancel() { cancelled_.store(true, std::memory_order_relaxed); }
  bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> cancelled_{false};
};

}  // namespace rover
