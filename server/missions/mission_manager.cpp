#include "server/missions/mission_manager.hpp"

#include <malloc.h>

#include <algorithm>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/coverage/coverage_entry.hpp"
#include "maps/geojson.hpp"
#include "maps/result_csv.hpp"
#include "server/errors/domain_error.hpp"
#include "server/exports/mission_mcap.hpp"
#include "server/json/area_json.hpp"
#include "server/json/plan_json.hpp"

namespace rover::missions {

namespace fs = std::filesystem;

namespace {
std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

// Seconds a client refused for a full queue or budget is told to wait (Retry-After): missions
// take from seconds to minutes, so a short retry is cheap and a long one would idle the workers.
constexpr std::chrono::seconds kRetryAfter{10};

MissionManager::MissionManager(store::Database& db, store::DataDir& dir,
                               const PlannerRegistry& registry, unsigned workers,
                               std::size_t queueCapacity, std::uint64_t memoryBudget)
    : db_(db), dir_(dir), registry_(registry), capacity_(queueCapacity), budget_(memoryBudget) {
  returnFreedMemoryPromptly();
  for (unsigned i = 0; i < std::max(1u, workers); ++i) workers_.emplace_back([this] { work(); });
}

MissionManager::~MissionManager() { stop(); }

void MissionManager::admit(const MemoryEstimate& estimate) const {
  std::lock_guard lock(mutex_);
  admitLocked(estimate);
}

namespace {

// What the client can change so the mission fits `budget`.
std::string remedy(const MemoryEstimate& e, std::uint64_t budget) {
  if (e.field == "params.max_steps" && e.bytesPerStep > 0 && e.fixedBytes < budget)
    return "give max_steps " + std::to_string((budget - e.fixedBytes) / e.bytesPerStep) +
           " or fewer (each rover moves at most once a step, and every move is kept for the result)";
  if (e.field == "params.coverage_cell") return "use a larger coverage_cell";
  if (e.field == "params.targets") return "use fewer targets or rovers";
  return "use a smaller map";
}

}  // namespace

void MissionManager::admitLocked(const MemoryEstimate& e) const {
  if (stopping_) throw DomainError(Refusal::Unavailable, "the server is shutting down");
  if (e.bytes > budget_)
    throw DomainError(Refusal::MissionTooLarge,
                      "the mission needs about " + formatBytes(e.bytes) + " (" + e.what +
                          "), more than the server's mission memory budget of " + formatBytes(budget_) + ": " +
                          remedy(e, budget_),
                      e.field);
  if (queue_.size() >= capacity_)
    throw DomainError(Refusal::QueueFull,
                      "the mission queue is full (" + std::to_string(capacity_) + " waiting); try again later")
        .retryAfter(kRetryAfter);
  if (reserved_ + e.bytes > budget_)
    throw DomainError(Refusal::MemoryBusy,
                      "the running and queued missions hold " + formatBytes(reserved_) + " of the " +
                          formatBytes(budget_) + " mission memory budget and this one needs about " +
                          formatBytes(e.bytes) + " (" + e.what + "); try again when one finishes")
        .retryAfter(kRetryAfter);
}

void MissionManager::submit(MissionJob job) {
  retryUnsaved();
  std::unique_lock lock(mutex_);
  admitLocked(job.memory);
  job.record.status = RunStatus::Queued;
  db_.insertMission(job.record);  // StorageFull on a full disk: nothing queued
  const GridGeometry& g = job.eventGrid;
  Active a;
  a.stream = std::make_shared<MissionStream>(job.record.id, g, static_cast<int>(job.problem.rovers.size()), job.pace);
  a.stream->setGridOrigin(job.window.origin);
  a.cancel = std::make_shared<CancelToken>();
  a.memoryBytes = job.memory.bytes;
  reserved_ += a.memoryBytes;
  active_[job.record.id] = a;
  queue_.push_back(std::move(job));
  lock.unlock();
  cv_.notify_one();
}

std::uint64_t MissionManager::memoryReserved() const {
  std::lock_guard lock(mutex_);
  return reserved_;
}

void MissionManager::recordStatus(const std::string& id, RunStatus status,
                                  const std::string& message, const nlohmann::json& metrics) {
  try {
    db_.updateMission(id, status, message, metrics);
    if (onStatus) onStatus(id, status);
    return;
  } catch (const std::exception&) {
    // A full (or failing) disk: the stream holds the status for clients; the row is retried.
  }
  if (status == RunStatus::Running) return;  // superseded by the final status anyway
  std::lock_guard lock(unsavedMutex_);
  unsaved_[id] = {status, message, metrics};
}

void MissionManager::retryUnsaved() {
  std::map<std::string, Unsaved> pending;
  {
    std::lock_guard lock(unsavedMutex_);
    pending.swap(unsaved_);
  }
  for (auto& [id, u] : pending) {
    try {
      db_.updateMission(id, u.status, u.message, u.metrics);
    } catch (const std::exception&) {
      std::lock_guard lock(unsavedMutex_);
      unsaved_.emplace(id, std::move(u));  // a newer status, if any, wins
    }
  }
}

void MissionManager::rememberFinished(const std::string& id, std::shared_ptr<MissionStream> stream) {
  finished_[id] = std::move(stream);
  finishedOrder_.push_back(id);
  while (finishedOrder_.size() > 32) {
    finished_.erase(finishedOrder_.front());
    finishedOrder_.pop_front();
  }
}

namespace {
const std::string kCancelledByRequest = "cancelled by request";
}  // namespace

MissionManager::CancelOutcome MissionManager::cancel(const std::string& id) {
  std::unique_lock lock(mutex_);
  auto it = active_.find(id);
  if (it == active_.end()) return CancelOutcome::NotActive;
  Active& a = it->second;
  if (a.cancelled || a.storing) return CancelOutcome::Finishing;
  a.cancel->cancel();
  a.stream->setCancelled();
  if (a.running) {
    // Final now, under the lock so the worker (which reads `cancelled` under it once its planner
    // returns) writes its partial result's row after this one. The planner stops within a step.
    a.cancelled = true;
    recordStatus(id, RunStatus::Cancelled, kCancelledByRequest);
    a.stream->setStatus(RunStatus::Cancelled);  // its "done" frame comes once the result is stored
    return CancelOutcome::Cancelled;
  }
  // Still queued: take it out and finish it here.
  for (auto q = queue_.begin(); q != queue_.end(); ++q)
    if (q->record.id == id) {
      queue_.erase(q);
      break;
    }
  auto stream = a.stream;
  reserved_ -= a.memoryBytes;
  active_.erase(it);
  lock.unlock();
  recordStatus(id, RunStatus::Cancelled, "cancelled before it started");
  stream->finish(RunStatus::Cancelled, "cancelled before it started", nullptr);
  std::lock_guard relock(mutex_);
  rememberFinished(id, stream);
  return CancelOutcome::Cancelled;
}

bool MissionManager::resultPending(const std::string& id) const {
  std::lock_guard lock(mutex_);
  return active_.count(id) > 0;
}

bool MissionManager::stopPlanning(const std::string& id) {
  std::lock_guard lock(mutex_);
  Active& a = active_.at(id);
  a.storing = true;
  return a.cancelled;
}

void MissionManager::forget(const std::string& id) {
  std::lock_guard lock(mutex_);
  finished_.erase(id);
  finishedOrder_.erase(std::remove(finishedOrder_.begin(), finishedOrder_.end(), id), finishedOrder_.end());
}

std::shared_ptr<MissionStream> MissionManager::stream(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    if (auto it = active_.find(id); it != active_.end()) return it->second.stream;
    if (auto it = finished_.find(id); it != finished_.end()) return it->second;
  }
  auto rec = db_.getMission(id);
  if (!rec) return nullptr;
  // A finished mission from an earlier run of the server: replay its stored final state.
  const fs::path dir = dir_.missionDir(id);
  nlohmann::json trails = nlohmann::json::array();
  if (fs::exists(dir / "trails.json")) trails = nlohmann::json::parse(readFile(dir / "trails.json"), nullptr, false);
  if (trails.is_discarded()) trails = nlohmann::json::array();
  std::string grid = fs::exists(dir / "grid.bin") ? readFile(dir / "grid.bin") : std::string();
  auto s = MissionStream::fromStored(id, grid, trails, rec->status, rec->message, rec->metrics);
  if (fs::exists(dir / "overlays.json"))
    s->restoreOverlays(nlohmann::json::parse(readFile(dir / "overlays.json"), nullptr, false));
  if (fs::exists(dir / "beliefs.json"))
    s->restoreBeliefs(nlohmann::json::parse(readFile(dir / "beliefs.json"), nullptr, false));
  if (fs::exists(dir / "window.json")) {
    const auto w = nlohmann::json::parse(readFile(dir / "window.json"), nullptr, false);
    if (w.is_object() && w.contains("origin") && w["origin"].is_array() && w["origin"].size() == 2 &&
        w["origin"][0].is_number() && w["origin"][1].is_number())
      s->setGridOrigin({w["origin"][0].get<double>(), w["origin"][1].get<double>()});
  }
  std::lock_guard lock(mutex_);
  rememberFinished(id, s);
  return s;
}

std::size_t MissionManager::running() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& [id, a] : active_) n += a.running;
  return n;
}

std::size_t MissionManager::queued() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

void MissionManager::work() {
  while (true) {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) return;
    MissionJob job = std::move(queue_.front());
    queue_.pop_front();
    Active& a = active_[job.record.id];
    a.running = true;
    // Running in the row and the stream before a cancel (which takes the lock) makes it final.
    recordStatus(job.record.id, RunStatus::Running, "");
    a.stream->setStatus(RunStatus::Running);
    Active copy = a;
    lock.unlock();
    runJob(job, copy);
  }
}

namespace {

// The warnings in one status message, bounded (result.json holds them all).
std::string outcomeSummary(const std::vector<std::string>& warnings) {
  constexpr std::size_t kShown = 4;
  std::string out;
  for (std::size_t i = 0; i < warnings.size() && i < kShown; ++i) out += (i ? "; " : "") + warnings[i];
  if (warnings.size() > kShown) out += "; and " + std::to_string(warnings.size() - kShown) + " more (result.json)";
  return out;
}

}  // namespace

void MissionManager::runJob(MissionJob& job, Active a) {
  const std::string id = job.record.id;
  retryUnsaved();
  RunStatus status = RunStatus::Succeeded;
  std::string message, failure;
  nlohmann::json metrics = nullptr;
  bool cancelledEarly = false;  // final (cancelled) since the request: the row and stream say so
  try {
    const Planner& planner = registry_.get(job.record.planner);
    if (job.build) {
      // The world is built now, not while the mission waited in the queue (it may be gigabytes).
      try {
        job.build(job);
      } catch (const std::exception& e) {
        throw std::runtime_error(std::string("cannot build what the planner plans on: ") + e.what());
      }
      job.build = nullptr;
    }
    // A mission in an area plans in its window's frame: what it reports is moved into the map's.
    const bool windowed = job.window.origin != Eigen::Vector2d::Zero();
    std::optional<ShiftedSink> shifted;
    if (windowed) shifted.emplace(*a.stream, job.window.origin);
    EventSink* sink = windowed ? static_cast<EventSink*>(&*shifted) : a.stream.get();
    PlanResult result = planner.run(job.problem, job.params, sink, a.cancel.get());
    if (windowed) shiftResult(result, job.window.origin);
    cancelledEarly = stopPlanning(id);
    job.problem.world = {};  // the result is saved below; the world is no longer needed
    job.problem.pdm.reset();  // (the DEM gives the CSV's heights and attitudes; dropped below)
    // Built once: on a fine grid the result's JSON is the biggest thing a mission holds.
    nlohmann::json resultJson = json::toJson(result);
    metrics = resultJson["metrics"];
    if (cancelledEarly) {
      status = RunStatus::Cancelled;
      message = kCancelledByRequest;
    } else if (result.cancelled || a.cancel->cancelled()) {
      bool shuttingDown;
      {
        std::lock_guard lock(mutex_);
        shuttingDown = stopping_;
      }
      status = shuttingDown ? RunStatus::Interrupted : RunStatus::Cancelled;
      message = shuttingDown ? "the server stopped while the mission was running" : kCancelledByRequest;
    } else if (!result.warnings.empty()) {
      // It ran to its end, but left something the user must be told (short or skipped legs,
      // unreachable ground, attitude exceedances…): not a plain success (issue 10).
      status = RunStatus::CompletedWithWarnings;
      message = outcomeSummary(result.warnings);
    }
    saveResult(job, result, std::move(resultJson), *a.stream);
    job.problem.dem.reset();
  } catch (const store::StorageFull& e) {
    failure = std::string("insufficient storage: ") + e.what();
  } catch (const std::exception& e) {
    failure = e.what();
  }
  if (!failure.empty()) {
    // A cancelled mission stays cancelled (a final status is not left): the message says why it
    // has no result.
    cancelledEarly = stopPlanning(id);
    status = cancelledEarly ? RunStatus::Cancelled : RunStatus::Failed;
    message = cancelledEarly ? kCancelledByRequest + "; no partial result: " + failure : failure;
  }
  recordStatus(id, status, message, metrics);
  a.stream->finish(status, message, metrics);
  job = MissionJob{};  // its request, rovers and params too, before the heap is trimmed
  // Give what the mission held back to the system before it is let go (so a client that sees it
  // ended sees its memory returned): glibc keeps freed memory in the worker's arena, so a mission
  // that peaked at gigabytes otherwise leaves the idle server there (issue 22: 1.77 GB idle after
  // a cancel). malloc_trim(0) releases the free pages inside every arena, the middle of the heap
  // included; the arenas' tops are kept small by returnFreedMemoryPromptly().
  ::malloc_trim(0);
  std::lock_guard lock(mutex_);
  reserved_ -= a.memoryBytes;
  active_.erase(id);
  rememberFinished(id, a.stream);
}

void MissionManager::saveResult(const MissionJob& job, const PlanResult& result,
                                nlohmann::json resultJson, const MissionStream& stream) {
  const std::string staging = dir_.stagingDir();
  try {
    writeResultFiles(job, result, std::move(resultJson), stream, staging);
    // Charged to the map's disk budget: beyond it the mission fails as on a full disk.
    dir_.commitDir(staging, dir_.missionDir(job.record.id), store::DiskCharge{store::DiskUse::Result, job.record.mapId, ""});
  } catch (...) {
    store::DataDir::removeTree(staging);  // a full disk must not also keep the half-written files
    throw;
  }
}

void MissionManager::writeResultFiles(const MissionJob& job, const PlanResult& result,
                                      nlohmann::json j, const MissionStream& stream,
                                      const std::string& staging) {
  const fs::path s(staging);
  j["mission"] = job.record.id;
  j["map"] = job.record.mapId;
  j["spec"] = job.record.spec;
  // Where it was planned (issue 24): the area as asked (null: the whole map) and the window of the
  // map the planner saw; every position in the result is in the map's frame.
  j["area"] = job.area ? json::areaToJson(*job.area) : nlohmann::json(nullptr);
  j["planning_window"] = json::windowToJson(job.window);
  store::DataDir::writeFileAtomic((s / "result.json").string(), j.dump());
  // The stream's grid lies at the window's origin; a replay from disk reads it here.
  store::DataDir::writeFileAtomic((s / "window.json").string(), j["planning_window"].dump());
  j = nullptr;  // free the tree before the other files are formatted
  store::DataDir::writeFileAtomic(
      (s / "result.geojson").string(),
      maps::missionToGeoJson(result, keepOutZones(job.record.spec), job.mapGrid, job.geo));
  std::vector<double> headings;
  for (const auto& r : job.problem.rovers) headings.push_back(r.heading);
  store::DataDir::writeFileAtomic(
      (s / "result.csv").string(),
      maps::resultCsv(result.tracks, job.mapGrid, job.geo, job.problem.dem.get(), headings, job.window.origin));
  // The replay for Foxglove/Lichtblick (issue 28), streamed to the staging folder chunk by chunk
  // (about 1 MB held) and committed, and charged to the map's disk budget, with the other files.
  exports::ReplayInput replay;
  replay.result = &result;
  replay.dem = job.problem.dem.get();
  replay.demOrigin = job.window.origin;
  replay.grid = job.mapGrid;
  replay.geo = job.geo;
  replay.zones = keepOutZones(job.record.spec);
  replay.startHeadings = headings;
  exports::writeReplayMcapFile(replay, (s / "replay.mcap").string());
  bool believed = false;
  for (const auto& t : result.tracks) believed = believed || !t.believed.empty();
  store::DataDir::writeFileAtomic((s / "grid.bin").string(), stream.fullGridFrame());
  store::DataDir::writeFileAtomic((s / "trails.json").string(), stream.trailsJson().dump());
  store::DataDir::writeFileAtomic((s / "overlays.json").string(), stream.overlaysJson().dump());
  if (believed)  // coverage under localisation error: the believed trails (issue 15)
    store::DataDir::writeFileAtomic((s / "beliefs.json").string(), stream.beliefsJson().dump());
}

// The mission's keep-out zones (request field `keep_out`: a GeoJSON FeatureCollection of Polygons
// in the local frame) for the exports; none when the request has none. The request was
// validated when it was accepted, so anything else is skipped rather than refused here.
std::vector<maps::Zone> keepOutZones(const nlohmann::json& spec) {
  std::vector<maps::Zone> out;
  if (!spec.is_object()) return out;
  auto fc = spec.find("keep_out");
  if (fc == spec.end() || !fc->is_object()) return out;
  auto features = fc->find("features");
  if (features == fc->end() || !features->is_array()) return out;
  for (const auto& f : *features) {
    if (!f.is_object() || !f.contains("geometry") || !f["geometry"].is_object()) continue;
    const auto& geom = f["geometry"];
    if (geom.value("type", "") != "Polygon" || !geom.contains("coordinates") || !geom["coordinates"].is_array())
      continue;
    maps::Zone z;
    for (const auto& ring : geom["coordinates"]) {
      if (!ring.is_array()) continue;
      auto& r = z.rings.emplace_back();
      for (const auto& p : ring)
        if (p.is_array() && p.size() >= 2 && p[0].is_number() && p[1].is_number())
          r.emplace_back(p[0].get<double>(), p[1].get<double>());
    }
    if (f.contains("properties") && f["properties"].is_object() && f["properties"].contains("name") &&
        f["properties"]["name"].is_string())
      z.name = f["properties"]["name"].get<std::string>();
    out.push_back(std::move(z));
  }
  return out;
}

void MissionManager::stop() {
  std::vector<std::pair<std::string, std::shared_ptr<MissionStream>>> queuedStreams;
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && workers_.empty()) return;
    stopping_ = true;
    for (auto& [id, a] : active_) {
      a.cancel->cancel();
      a.stream->setCancelled();
      if (!a.running) queuedStreams.emplace_back(id, a.stream);
    }
    queue_.clear();
  }
  cv_.notify_all();
  for (auto& t : workers_)
    if (t.joinable()) t.join();
  workers_.clear();
  for (auto& [id, s] : queuedStreams) {
    recordStatus(id, RunStatus::Interrupted, "the server stopped before the mission started");
    s->finish(RunStatus::Interrupted, "the server stopped before the mission started", nullptr);
  }
  retryUnsaved();  // whatever is still refused is marked interrupted at the next start
}

}  // namespace rover::missions
