#pragma once
// The legs of every rover planned ahead from their nominal starts (each leg from the previous
// leg's goal) on worker threads, while the coordinator works through the rovers in priority order
// (ours, issue 10). Each leg is its own planning problem with its own seed, so the plans are those
// of planning each leg alone, whichever thread runs it and whenever; the coordinator asks for
// them in the order the workers take them, so planning and coordinating overlap instead of one
// waiting for the other (a hybrid mission spent ~3.4 s planning on two threads, then ~3 s
// coordinating on one).
// The workers also take the re-plan the coordinator is likely to ask for next (speculate): a leg
// whose tries keep failing with the same keep-out zones asks for the same problem with the next
// seed, and two threads then plan two tries at once. A plan is a function of its request alone,
// so the coordinator's results do not depend on which thread made it, or whether one was made
// ahead at all.
#include <Eigen/Core>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/team/leg_planner.hpp"

namespace rover::team {

class PlanAhead {
 public:
  struct Job {
    Eigen::Vector2d start{0, 0};  // the leg's nominal start
    double heading = 0;           // the rover's heading there
    Eigen::Vector2d goal{0, 0};
    std::uint64_t seed = 0;
    bool planned = true;          // false: nothing to plan (a via leg the rover may drive as given)
    std::vector<KeepOutZone> keepOut;  // zones the plan stays out of from the first try
  };
  // Starts `workers` threads (0: none; every plan is then made by the thread that asks for it).
  // `planner` must be safe to call from several threads and outlive this object. Destroyed
  // without finish() (an error while coordinating), the workers stop after their current plan.
  PlanAhead(const LegPlanner& planner, std::vector<Job> jobs, unsigned workers,
            const CancelToken* cancel);
  ~PlanAhead();
  PlanAhead(const PlanAhead&) = delete;
  PlanAhead& operator=(const PlanAhead&) = delete;

  // One planning problem, as LegPlanner::plan takes it.
  struct Request {
    Eigen::Vector2d from{0, 0};
    double heading = 0;
    Eigen::Vector2d goal{0, 0};
    std::uint64_t seed = 0;
    std::vector<KeepOutZone> keepOut;
    bool operator==(const Request& o) const;
  };

  const Job& job(std::size_t j) const { return jobs_[j]; }
  // The plan of job j (nullptr when it is not planned): made by the calling thread if no worker
  // has started it, else waited for. Rethrows what its planning threw.
  const PathResult* get(std::size_t j);
  // A re-plan likely asked for next: a worker plans it when one is free (before further leg
  // jobs). It replaces any earlier speculation no thread has started. Without workers, nothing.
  void speculate(Request r);
  // The plan for `r`: the speculated one if it matches (waited for, while this thread plans the
  // next speculation or leg job), else planned by the calling thread. Rethrows planning errors.
  PathResult plan(const Request& r);
  // Makes or waits for every remaining plan (so the number of plans made does not depend on the
  // threads) and joins the workers; returns that number. Rethrows the first planning error.
  int finish();

 private:
  enum State : int { Pending, Running, Done };
  struct Speculation {
    Request request;
    State state = Pending;  // under mutex_
    PathResult result;
    std::exception_ptr error;
  };
  void run(std::size_t j);  // plans job j (the caller has claimed it)
  void run(Speculation& s);  // plans it (the caller has claimed it)
  // Claims the next pending leg job or speculation and plans it; false when there is none.
  bool helpOnce(bool speculations);
  std::shared_ptr<Speculation> claimSpeculation();  // under mutex_
  void work();

  const LegPlanner& planner_;
  std::vector<Job> jobs_;
  const CancelToken* cancel_;
  std::vector<PathResult> results_;
  std::vector<std::exception_ptr> errors_;
  std::unique_ptr<std::atomic<int>[]> state_;
  std::atomic<std::size_t> next_{0};
  std::atomic<bool> stop_{false};  // the destructor or finish(): take no more jobs
  std::mutex mutex_;
  std::condition_variable done_;  // a job or speculation is done, one is pending, or stop_
  // Speculations not yet taken: at most one pending, and those the workers run or ran (bounded
  // by the workers; dropped at the next speculate()).
  std::deque<std::shared_ptr<Speculation>> speculations_;
  std::vector<std::thread> workers_;
};

}  // namespace rover::team
