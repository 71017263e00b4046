#pragma once
// Runs a study's runs (issue 12): each run builds its problem with the one problem builder
// (server/problems), runs the planner from the registry by name and becomes one RunRow. A run is a
// pure function of (spec, run index): the same rows come out on 1 or N threads, in shards, or on
// MPI ranks (study_mpi.hpp); only wall_s, cpu_s, host and rank differ.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/planning/planner.hpp"
#include "server/studies/study_db.hpp"
#include "server/studies/study_spec.hpp"

namespace rover::studies {

struct RunOptions {
  unsigned threads = 0;  // worker threads; 0 = all cores
  // Job arrays: only the runs with run_index % shardCount == shardIndex (0-based).
  int shardIndex = 0;
  int shardCount = 1;
  const CancelToken* cancel = nullptr;  // stops taking runs; a run in flight is cancelled too
  double commitSeconds = 1.0;           // a batch is committed at least this often ...
  std::size_t commitRuns = 1000;        // ... or when it holds this many runs
  int rank = 0;                         // written to each row (MPI rank)
};

// done = runs of the shard in the database (previous sessions included), total = runs of the shard.
using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

struct RunReport {
  std::size_t total = 0;        // runs in the shard
  std::size_t alreadyDone = 0;  // found in the database at the start (a resume)
  std::size_t ran = 0;          // run and committed now
  double wallSeconds = 0;
  bool cancelled = false;
};

class StudyRunner {
 public:
  // Builds what every run shares: the maps of terrain/dem worlds (loaded once), the coverage
  // worlds laid on them. Throws rover::Error naming the world ("worlds[1].dem") when one fails.
  explicit StudyRunner(StudySpec spec);
  const StudySpec& spec() const { return spec_; }

  // One run; thread-safe. nullopt when `cancel` stopped it (nothing of it is kept).
  std::optional<RunRow> runOne(std::size_t runIndex, const CancelToken* cancel = nullptr) const;

  // The shard's run indices not yet in `db`, ascending.
  std::vector<std::size_t> pending(const StudyDb& db, int shardIndex = 0, int shardCount = 1) const;

  // Runs the pending runs of the shard on options.threads threads and commits them to `db`
  // (attached to the spec first) in batches; `progress` is called on the calling thread after
  // each commit. Throws the first run's exception, after committing the runs already done.
  RunReport run(StudyDb& db, const RunOptions& options, const ProgressFn& progress = {}) const;

  // The work loop under run() and the MPI ranks: `threads` workers take indices from `next` until
  // it returns nullopt and hand each row to `done` (called concurrently: must be thread-safe).
  // Returns when every worker has stopped; rethrows the first exception.
  void work(unsigned threads, const std::function<std::optional<std::size_t>()>& next,
            const std::function<void(RunRow&&)>& done, const CancelToken* cancel, int rank) const;

 private:
  StudySpec spec_;
  PlannerRegistry registry_;
  std::vector<std::shared_ptr<const terrain::Dem>> maps_;   // per world; null for grid worlds
  std::vector<std::shared_ptr<const PlanningProblem>> mapProblems_;  // per config: coverage on a map
  std::string host_;
};

}  // namespace rover::studies
