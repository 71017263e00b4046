#pragma once
// Runs missions on a pool of workers (issue: server, "Mission manager"): a bounded queue (full ->
// 429), cancellation through the planner's token, a failing planner marks only its mission failed.
// Results are written atomically into the mission's folder before its row says "succeeded".
//
// A cancel is final at once (issue 22, "cancel within 1 s"): the row and the stream's status say
// "cancelled" before cancel() returns, whatever the mission's size, and the worker stores the
// partial result afterwards (its path, JSON, GeoJSON and CSV: seconds for a long mission). Until
// the files are committed the mission stays active here — resultPending() is true, its result
// files answer 409 not_ready, its stream's "done" frame (the page's cue to fetch the result) comes
// once they are there, and its memory stays reserved — so no client reads a half-written result.
// Chosen over streaming the result to disk during the run: the result's formats are built from
// the whole plan (metrics, incidents, the GeoJSON's lines), and writing them as the planner goes
// would cost every mission I/O on its steps to speed up the cancelled ones.
//
// Memory is bounded and stated (issue 14): a queued mission holds its request, not its world — the
// world / DEM / PDM are built by `MissionJob::build` when a worker starts it — and every mission's
// estimated memory (mission_memory.hpp) is counted against a budget while it is queued or running:
// one mission over the budget is refused mission_too_large, a full budget memory_busy with a
// retry-after (DomainError). A full disk never stops the server: writes throw StorageFull, a worker that cannot store its result
// marks the mission failed (or keeps the status in memory and retries the row later).
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/planning/mission_area.hpp"
#include "core/planning/planner.hpp"
#include "maps/geojson.hpp"
#include "server/missions/mission_memory.hpp"
#include "server/missions/mission_stream.hpp"
#include "server/store/data_dir.hpp"
#include "server/store/database.hpp"

namespace rover::missions {

// The keep-out zones of a mission request (its `keep_out`: a GeoJSON FeatureCollection of
// Polygons in the local frame), for the exports; none when it has none.
std::vector<maps::Zone> keepOutZones(const nlohmann::json& spec);

struct MissionJob {
  store::MissionRecord record;  // id, map, planner, spec (as accepted)
  // Validated. While queued it holds the rovers only: world, dem and pdm are filled in by `build`
  // when a worker starts the mission, and dropped when it ends.
  PlanningProblem problem;
  ParamSet params;
  GeoReference geo;             // the map's georeferencing, for the GeoJSON result
  GridGeometry mapGrid;         // the grid positions are relative to (for the GeoJSON result)
  // Where the planner plans (issue 24, core/planning/mission_area.hpp): the whole map, or the
  // planning window of the mission's area. `problem` is in the window's frame; the result and
  // the stream's positions are moved into the map's by the window's origin.
  PlanningWindow window;
  std::optional<MissionArea> area;
  GridGeometry eventGrid;       // the planner's cellsChanged grid (Planner::eventGrid)
  double pace = 0;              // steps per second, 0 = full speed
  MemoryEstimate memory;        // estimated peak while it runs (counted against the budget)
  // Builds what the planner plans on into `problem` (throws, e.g. when the map was deleted while
  // the mission waited: the mission is then marked failed with the reason). Null: already built.
  std::function<void(MissionJob&)> build;
};

class MissionManager {
 public:
  // `memoryBudget`: bytes that running + queued missions may hold together (their estimates).
  MissionManager(store::Database& db, store::DataDir& dir, const PlannerRegistry& registry,
                 unsigned workers, std::size_t queueCapacity,
                 std::uint64_t memoryBudget = defaultMissionMemoryBudget());
  ~MissionManager();  // stop()

  // Throws DomainError mission_too_large when one mission's estimate exceeds the budget,
  // queue_full or memory_busy (with a retry-after) when the queue is full or the running + queued
  // missions leave too little of the budget, unavailable once stopping. Cheap: callers check before they build anything big; submit() checks again.
  void admit(const MemoryEstimate& estimate) const;
  // Queues a validated mission (row inserted as "queued"); throws like admit(), and StorageFull when
  // the row cannot be written (full disk).
  void submit(MissionJob job);
  enum class CancelOutcome {
    Cancelled,  // it was queued or running: its status is "cancelled" now
    Finishing,  // it has stopped planning (cancelled before, or ran to its end) and stores its result
    NotActive,  // not queued or running (ended, or unknown)
  };
  // Cancels a queued or running mission: its status is final when this returns (see above).
  CancelOutcome cancel(const std::string& id);
  // True while the mission is queued, running or storing its result (a cancelled one after its
  // final status too): its result files are not there yet but may come.
  bool resultPending(const std::string& id) const;
  // A deleted mission: its finished stream is dropped, so no subscriber replays it.
  void forget(const std::string& id);
  // The stream of a live or finished mission (finished ones rebuilt from disk); null if unknown.
  std::shared_ptr<MissionStream> stream(const std::string& id);
  std::size_t running() const;
  std::size_t queued() const;
  std::uint64_t memoryBudget() const { return budget_; }
  std::uint64_t memoryReserved() const;  // estimates of the running + queued missions
  // Cancels everything, marks running/queued missions interrupted, joins the workers.
  void stop();
  // Told every status a mission's row is given (the API's event stream, issue 26); set before the
  // first submit. Runs on the worker (or the cancelling request's) thread; must not throw.
  std::function<void(const std::string& id, RunStatus status)> onStatus;

 private:
  struct Active {
    std::shared_ptr<MissionStream> stream;
    std::shared_ptr<CancelToken> cancel;
    bool running = false;
    bool cancelled = false;  // cancelled while it ran: the row already says so
    bool storing = false;    // the planner has returned: a cancel comes too late
    std::uint64_t memoryBytes = 0;
  };
  // The planner has returned: no cancel changes the outcome from now on. True if a cancel request
  // already made the mission final (cancelled) while it ran.
  bool stopPlanning(const std::string& id);
  void admitLocked(const MemoryEstimate& estimate) const;  // caller holds mutex_
  void work();
  void runJob(MissionJob& job, Active active);
  void saveResult(const MissionJob& job, const PlanResult& result, nlohmann::json resultJson,
                  const MissionStream& stream);
  static void writeResultFiles(const MissionJob& job, const PlanResult& result, nlohmann::json j,
                               const MissionStream& stream, const std::string& staging);
  void rememberFinished(const std::string& id, std::shared_ptr<MissionStream> stream);  // holds mutex_
  // Writes a mission's status row; on a storage failure keeps it in `unsaved_` (retried by the
  // next write) instead of throwing, so a full disk never takes a worker (or the process) down.
  void recordStatus(const std::string& id, RunStatus status, const std::string& message,
                    const nlohmann::json& metrics = nullptr);
  void retryUnsaved();

  store::Database& db_;
  store::DataDir& dir_;
  const PlannerRegistry& registry_;
  const std::size_t capacity_;
  const std::uint64_t budget_;
  mutable std::mutex mutex_;
  std::uint64_t reserved_ = 0;  // sum of Active::memoryBytes
  std::condition_variable cv_;
  std::deque<MissionJob> queue_;
  std::map<std::string, Active> active_;
  std::map<std::string, std::shared_ptr<MissionStream>> finished_;  // recent, bounded
  std::deque<std::string> finishedOrder_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  struct Unsaved {
    RunStatus status;
    std::string message;
    nlohmann::json metrics;
  };
  std::mutex unsavedMutex_;
  std::map<std::string, Unsaved> unsaved_;  // final statuses the database refused (full disk)
};

}  // namespace rover::missions
