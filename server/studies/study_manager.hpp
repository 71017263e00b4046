#pragma once
// The server's studies (issue 12): POST /api/studies queues a study, one runs at a time, below the
// missions in priority, and a restart resumes what was unfinished. Built on the engine's public
// interface (studies.hpp); nothing here plans.
//
// Where a study lives: StudyStore (DATA/studies/ID/). Never a client-chosen path: the id is the
// server's (DataDir::newId), and specs naming DEM files are refused.
//
// The parts: the store (persistence), the scheduler (one study at a time, first queued first, on
// a thread of its own), an executor (in-process, below the missions, or a launched command such
// as `serve --study-launcher "mpirun -np 16 --hostfile H"`: study_executor.hpp) and each study's
// live stream (StudyStream). This class keeps the studies' states and ties the parts together.
//
// Bounds (stated in README "Studies"): kMaxServerRuns runs per study, kMaxActive studies queued or
// running, kMaxStored studies kept; one study runs at a time.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/cancel.hpp"
#include "server/http/http_types.hpp"
#include "server/store/data_dir.hpp"
#include "server/store/database.hpp"
#include "server/studies/command_line.hpp"
#include "server/studies/study_executor.hpp"
#include "server/studies/study_scheduler.hpp"
#include "server/studies/study_spec.hpp"
#include "server/studies/study_state.hpp"
#include "server/studies/study_store.hpp"
#include "server/studies/study_stream.hpp"

namespace rover::studies {

constexpr std::size_t kMaxServerRuns = 200'000;  // runs (configurations × runs) of one study
constexpr std::size_t kMaxActive = 4;            // studies queued or running
constexpr std::size_t kMaxStored = 100;          // studies kept (delete ended ones for room)

class StudyManager : private StudyReporter {
 public:
  // `missionsBusy`: true while missions should have the machine (a mission waits, or they use
  // every core). `launcher`: empty = in-process; else argv prefix of the study command. `selfExe`:
  // the roverplan binary the launcher runs.
  StudyManager(store::DataDir& dir, std::function<bool()> missionsBusy,
               std::vector<std::string> launcher = {}, std::string selfExe = "/proc/self/exe");
  ~StudyManager() override;  // stop()

  // Checks the server's bounds (DomainError: the disk budget, runs per study, studies active or
  // kept), stores and queues a study read at the API edge (server/api/study_routes.cpp); returns
  // its state.
  StudyState submit(const StudySpec& spec);
  std::vector<StudyState> list() const;  // newest first
  std::optional<StudyState> get(const std::string& id) const;
  nlohmann::json specJson(const std::string& id) const;
  // The study database's summary (partial while it runs); null when it holds no run yet. Served
  // from memory (issue 22: it cost a pass over every run, 2.5 s on a 200 k-run study, at every
  // GET): a study running in the server publishes it after each commit (SummaryAccumulator, a few
  // ms), one run by a launcher every few seconds as it polls; an ended one keeps it in
  // summary.json. Only the first read of a study not running since the start (or of a folder
  // written by an older version) reads the database, once however many ask at the same time.
  nlohmann::json summary(const std::string& id);
  // runs.csv written (streamed) into the study's folder; returns its path.
  std::string runsCsvFile(const std::string& id) const;
  std::string benchmarkDbFile(const std::string& id) const;  // empty when there is no database yet
  std::string databasePath(const std::string& id) const;  // empty when there is none yet
  std::shared_ptr<StudyStream> stream(const std::string& id) const;

  // The rename of a client that read version `expected` (issue 26): its state.json written first
  // (a full disk throws and changes nothing), then the state it answers with. Cas::Stale and
  // Missing change nothing; `out` is the state after (the current one when stale).
  store::Cas rename(const std::string& id, const std::string& name, long long expected, StudyState& out);

  enum class Removal { NotFound, Cancelling, Deleted };
  // An active study is cancelled (the runs done stay); an ended one is deleted with its files.
  Removal remove(const std::string& id);

  // Stops the running study (it stays unfinished: the next start resumes it), joins the thread.
  void stop();

 private:
  struct Entry {
    StudyState state;
    std::shared_ptr<StudyStream> stream;
    std::shared_ptr<CancelToken> cancel;
    std::shared_ptr<const nlohmann::json> summary;  // null until published or first read
    std::uint64_t summaryVersion = 0;                // counts publishSummary calls
    std::shared_ptr<std::mutex> summaryOnce = std::make_shared<std::mutex>();  // one first read at a time
  };
  // StudyReporter, called by the executor on the scheduler's thread.
  void publishSummary(const std::string& id, const nlohmann::json& summary) override;
  void report(const std::string& id, std::size_t done, std::size_t total, std::size_t doneAtStart,
              StudyClock::time_point start, const std::function<nlohmann::json()>& summaryOf,
              StudyClock::time_point& lastSummary) override;
  void runOne(const std::string& id);  // the scheduler's: running, executed, ended
  void finish(const std::string& id, RunStatus status, const std::string& message);

  StudyStore store_;
  std::unique_ptr<StudyExecutor> executor_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> studies_;
  StudyScheduler scheduler_;  // last: its thread starts once the rest is constructed
};

}  // namespace rover::studies
