#pragma once
// How a server study's runs are carried out (StudyManager): in the server's process, one run at
// a time on the study thread (InProcessExecutor), or by a launched command such as mpirun that
// runs `roverplan study run` into the study's database (LaunchedExecutor). Either resumes: only
// the runs missing from the database are run.
#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/cancel.hpp"
#include "server/studies/study_store.hpp"

namespace rover::studies {

using StudyClock = std::chrono::steady_clock;
constexpr auto kSummaryEvery = std::chrono::seconds(3);  // partial summary on the stream

// What an executor tells the manager as the runs are stored.
class StudyReporter {
 public:
  virtual ~StudyReporter() = default;
  // The summary of the runs stored, for the GETs.
  virtual void publishSummary(const std::string& id, const nlohmann::json& summary) = 0;
  // Progress: `done` of `total` stored, `doneAtStart` of them before this session began at
  // `start` (the rate and ETA count this session only); pushes summaryOf() to the stream when
  // kSummaryEvery has passed since `lastSummary`.
  virtual void report(const std::string& id, std::size_t done, std::size_t total, std::size_t doneAtStart,
                      StudyClock::time_point start, const std::function<nlohmann::json()>& summaryOf,
                      StudyClock::time_point& lastSummary) = 0;
};

class StudyExecutor {
 public:
  virtual ~StudyExecutor() = default;
  // Runs the study's missing runs until they are stored or `cancel` is set; throws rover::Error
  // (the study failed, with its message), store::StorageFull / OverBudget (the disk) or another
  // exception (an internal error).
  virtual void run(const std::string& id, const CancelToken& cancel, StudyReporter& reporter) = 0;
  // Whether a run may plan on several threads (a launched command has the cluster's cores).
  virtual bool multithreadedRuns() const = 0;
};

// On the study thread, one run at a time, below the missions: the next run is taken only when
// `missionsBusy` says no mission is waiting and they leave a core free, so a mission never waits
// behind a study; a run in flight is not preempted (runs of the presets take milliseconds to a
// few seconds). Runs are committed in batches, and the summary follows the commits.
class InProcessExecutor : public StudyExecutor {
 public:
  InProcessExecutor(const StudyStore& store, std::function<bool()> missionsBusy)
      : store_(store), missionsBusy_(std::move(missionsBusy)) {}
  void run(const std::string& id, const CancelToken& cancel, StudyReporter& reporter) override;
  bool multithreadedRuns() const override { return false; }

 private:
  const StudyStore& store_;
  std::function<bool()> missionsBusy_;
};

// The launcher's argv + `roverplan study run --spec spec.json --out study.sqlite --quiet`, a child
// process started without a shell, its output in launcher.log; its progress is read from the
// database the child writes. Cancelling (or the disk budget) sends it SIGTERM.
class LaunchedExecutor : public StudyExecutor {
 public:
  // `selfExe`: the roverplan binary the launcher runs ("/proc/self/exe": this one, by its real path).
  LaunchedExecutor(const StudyStore& store, std::vector<std::string> launcher, std::string selfExe);
  void run(const std::string& id, const CancelToken& cancel, StudyReporter& reporter) override;
  bool multithreadedRuns() const override { return true; }

 private:
  const StudyStore& store_;
  std::vector<std::string> launcher_;
  std::string selfExe_;
};

}  // namespace rover::studies
