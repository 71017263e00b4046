#include "core/team/plan_ahead.hpp"

#include <algorithm>

namespace rover::team {

bool PlanAhead::Request::operator==(const Request& o) const {
  auto same = [](const KeepOutZone& a, const KeepOutZone& b) {
    return a.centre == b.centre && a.radius == b.radius;
  };
  return from == o.from && heading == o.heading && goal == o.goal && seed == o.seed &&
         std::equal(keepOut.begin(), keepOut.end(), o.keepOut.begin(), o.keepOut.end(), same);
}

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
  {
    std::lock_guard lock(mutex_);
    stop_.store(true);
  }
  done_.notify_all();
  for (auto& w : workers_) w.join();
}

void PlanAhead::run(std::size_t j) {
  const Job& job = jobs_[j];
  try {
    // Once cancelled, the jobs left are not planned at all: each would still run its guide
    // search before RRT* saw the token (64 rovers × 10 000 targets: minutes after a cancel).
    if (!(cancel_ && cancel_->cancelled()))
      results_[j] = planner_.plan(job.start, job.heading, job.goal, job.seed, job.keepOut, cancel_);
  } catch (...) {
    errors_[j] = std::current_exception();
  }
  {
    std::lock_guard lock(mutex_);
    state_[j].store(Done);
  }
  done_.notify_all();
}

void PlanAhead::run(Speculation& s) {
  PathResult result;
  std::exception_ptr error;
  const Request& r = s.request;  // never changed after speculate()
  try {
    if (!(cancel_ && cancel_->cancelled()))
      result = planner_.plan(r.from, r.heading, r.goal, r.seed, r.keepOut, cancel_);
  } catch (...) {
    error = std::current_exception();
  }
  {
    std::lock_guard lock(mutex_);
    s.result = std::move(result);
    s.error = error;
    s.state = Done;
  }
  done_.notify_all();
}

std::shared_ptr<PlanAhead::Speculation> PlanAhead::claimSpeculation() {
  for (auto& s : speculations_)
    if (s->state == Pending) {
      s->state = Running;
      return s;
    }
  return nullptr;
}

// A speculation first (it is wanted now, if at all), then the leg jobs in order.
bool PlanAhead::helpOnce(bool speculations) {
  if (speculations) {
    std::shared_ptr<Speculation> s;
    {
      std::lock_guard lock(mutex_);
      s = claimSpeculation();
    }
    if (s) {
      run(*s);
      return true;
    }
  }
  for (std::size_t h; (h = next_.fetch_add(1)) < jobs_.size();) {
    int pending = Pending;
    if (state_[h].compare_exchange_strong(pending, Running)) {
      run(h);
      return true;
    }
  }
  return false;
}

void PlanAhead::work() {
  auto pending = [&] {
    return std::any_of(speculations_.begin(), speculations_.end(),
                       [](const auto& s) { return s->state == Pending; });
  };
  while (!stop_.load()) {
    if (helpOnce(true)) continue;
    // No leg job is left (none are added): sleep until a speculation comes, or the end.
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return stop_.load() || pending(); });
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
      if (helpOnce(false)) continue;
      std::unique_lock lock(mutex_);
      done_.wait(lock, [&] { return state_[j].load() == Done; });
    }
  }
  if (errors_[j]) std::rethrow_exception(errors_[j]);
  return &results_[j];
}

void PlanAhead::speculate(Request r) {
  if (workers_.empty()) return;
  {
    std::lock_guard lock(mutex_);
    std::erase_if(speculations_, [](const auto& s) { return s->state == Pending; });
    // Bounded: a few finished ones the coordinator may still ask for, and the running ones.
    constexpr std::size_t kKept = 4;
    while (speculations_.size() >= kKept + workers_.size()) {
      const auto done = std::find_if(speculations_.begin(), speculations_.end(),
                                     [](const auto& s) { return s->state == Done; });
      if (done == speculations_.end()) break;
      speculations_.erase(done);
    }
    auto s = std::make_shared<Speculation>();
    s->request = std::move(r);
    speculations_.push_back(std::move(s));
  }
  done_.notify_all();
}

PathResult PlanAhead::plan(const Request& r) {
  std::shared_ptr<Speculation> mine;
  bool claimed = false;
  {
    std::lock_guard lock(mutex_);
    const auto it = std::find_if(speculations_.begin(), speculations_.end(),
                                 [&](const auto& s) { return s->request == r; });
    if (it != speculations_.end()) {
      mine = *it;
      speculations_.erase(it);
      if (mine->state == Pending) {
        mine->state = Running;
        claimed = true;
      }
    }
  }
  if (!mine) return planner_.plan(r.from, r.heading, r.goal, r.seed, r.keepOut, cancel_);
  if (claimed) run(*mine);
  // A worker is on it: this thread plans the next speculation (the try after this one) or leg
  // job meanwhile, so both threads plan.
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (mine->state == Done) break;
    }
    if (helpOnce(true)) continue;
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return mine->state == Done; });
  }
  std::lock_guard lock(mutex_);
  if (mine->error) std::rethrow_exception(mine->error);
  return std::move(mine->result);
}

int PlanAhead::finish() {
  while (helpOnce(false)) {
  }  // this thread plans what is left of the leg jobs
  for (std::size_t j = 0; j < jobs_.size(); ++j) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return state_[j].load() == Done; });
  }
  {
    std::lock_guard lock(mutex_);
    stop_.store(true);
    speculations_.clear();
  }
  done_.notify_all();
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
