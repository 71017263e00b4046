#include "core/team/plan_ahead.hpp"

namespace rover::team {

PlanAhead::PlanAhead(const LegPlanner& planner, std::vector<Job> jobs, unsigned workers,
                     const CancelToken* cancel)
    : planner_(planner),
      jobs_(std::move(jobs)),
      cancel_(cancel),
      results_(jobs_.size()),
      errors_(jobs_.size()),
      state_(new std::atomic<int>[jobs_.size()]) {
  for (std::size_t j = 0; j < jobs_.size(); ++j) state_[j].store(jobs_[j].planned ? Pending : Done);
  for (unsigned w = 0; w < workers; ++w) workers_.emplace_back([this] { work(); });
}

PlanAhead::~PlanAhead() {
  stop_.store(true);
  for (auto& w : workers_) w.join();
}

void PlanAhead::run(std::size_t j) {
  const Job& job = jobs_[j];
  try {
    results_[j] = planner_.plan(job.start, job.heading, job.goal, job.seed, {}, cancel_);
  } catch (...) {
    errors_[j] = std::current_exception();
  }
  {
    std::lock_guard lock(mutex_);
    state_[j].store(Done);
  }
  done_.notify_all();
}

// Takes the jobs in order, skipping those another thread has claimed.
void PlanAhead::work() {
  for (std::size_t j; !stop_.load() && (j = next_.fetch_add(1)) < jobs_.size();) {
    int expected = Pending;
    if (state_[j].compare_exchange_strong(expected, Running)) run(j);
  }
}

const PathResult* PlanAhead::get(std::size_t j) {
  if (!jobs_[j].planned) return nullptr;
  int expected = Pending;
  if (state_[j].compare_exchange_strong(expected, Running)) {
    run(j);
  } else {
    // A worker is on it: plan the next jobs meanwhile instead of idling (waiting alone left one
    // of two threads idle at the frontier and made team-search missions 0.5 s slower).
    while (state_[j].load() != Done) {
      const std::size_t h = next_.fetch_add(1);
      if (h < jobs_.size()) {
        int pending = Pending;
        if (state_[h].compare_exchange_strong(pending, Running)) run(h);
        continue;
      }
      std::unique_lock lock(mutex_);
      done_.wait(lock, [&] { return state_[j].load() == Done; });
    }
  }
  if (errors_[j]) std::rethrow_exception(errors_[j]);
  return &results_[j];
}

int PlanAhead::finish() {
  work();  // this thread helps with what is left
  for (std::size_t j = 0; j < jobs_.size(); ++j) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return state_[j].load() == Done; });
  }
  for (auto& w : workers_) w.join();
  workers_.clear();
  int planned = 0;
  for (std::size_t j = 0; j < jobs_.size(); ++j) {
    if (errors_[j]) std::rethrow_exception(errors_[j]);
    planned += jobs_[j].planned ? 1 : 0;
  }
  return planned;
}

}  // namespace rover::team
