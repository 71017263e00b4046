#pragma once
// Runs missions on a pool of workers (issue: server, "Mission manager"): a bounded queue (full ->
// 429), cancellation through the planner's token, a failing planner marks only its mission failed.
// Results are written atomically into the mission's folder before its row says "succeeded".
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/planning/planner.hpp"
#include "server/missions/mission_stream.hpp"
#include "server/store/data_dir.hpp"
#include "server/store/database.hpp"

namespace rover::missions {

struct MissionJob {
  store::MissionRecord record;  // id, map, planner, spec (as accepted)
  PlanningProblem problem;      // validated
  ParamSet params;
  GeoReference geo;             // the map's georeferencing, for the GeoJSON result
  GridGeometry mapGrid;         // the grid positions are relative to (for the GeoJSON result)
  GridGeometry eventGrid;       // the planner's cellsChanged grid (Planner::eventGrid)
  double pace = 0;              // steps per second, 0 = full speed
};

class MissionManager {
 public:
  MissionManager(store::Database& db, store::DataDir& dir, const PlannerRegistry& registry,
                 unsigned workers, std::size_t queueCapacity);
  ~MissionManager();  // stop()

  // Queues a validated mission (row inserted as "queued"); throws http::ApiError 429 when full.
  void submit(MissionJob job);
  // Cancels a queued or running mission; false if it is not (or no longer) active.
  bool cancel(const std::string& id);
  // The stream of a live or finished mission (finished ones rebuilt from disk); null if unknown.
  std::shared_ptr<MissionStream> stream(const std::string& id);
  std::size_t running() const;
  std::size_t queued() const;
  // Cancels everything, marks running/queued missions interrupted, joins the workers.
  void stop();

 private:
  struct Active {
    std::shared_ptr<MissionStream> stream;
    std::shared_ptr<CancelToken> cancel;
    bool running = false;
  };
  void work();
  void runJob(MissionJob& job, Active active);
  void saveResult(const MissionJob& job, const PlanResult& result, const MissionStream& stream);

  store::Database& db_;
  store::DataDir& dir_;
  const PlannerRegistry& registry_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<MissionJob> queue_;
  std::map<std::string, Active> active_;
  std::map<std::string, std::shared_ptr<MissionStream>> finished_;  // recent, bounded
  std::deque<std::string> finishedOrder_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace rover::missions
