#pragma once
// The background writer of stored maps' COGs (issue 24): an import announces its map with the
// elevation raw (server/api/map_files.hpp kRawDemDir) and queues it here; one thread then writes
// each map's dem.tif in turn, in the order queued. One job at a time, so memory is one COG
// write's (GDAL's block cache, capped at GDAL_CACHEMAX, 256 MiB by default, plus the COG driver's
// buffers: a few 256-row strips), whatever the number of maps waiting.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace rover::api {

class ElevationCompressor {
 public:
  // `job(mapId, cancelled)` writes one map's COG; it polls `cancelled` while it works and stops
  // when it says so. Its exceptions are its own to report (they are logged here, not rethrown).
  using Job = std::function<void(const std::string& mapId, const std::function<bool()>& cancelled)>;
  explicit ElevationCompressor(Job job);
  // Cancels the running job, drops the queue and joins the thread (a map left raw is queued
  // again at the next start).
  ~ElevationCompressor();
  ElevationCompressor(const ElevationCompressor&) = delete;
  ElevationCompressor& operator=(const ElevationCompressor&) = delete;

  // What the destructor does, earlier: for an owner whose callbacks die before the compressor.
  void stop();

  // Queues the map (once: a map already queued or running is not queued again).
  void enqueue(const std::string& mapId);
  // Drops the map from the queue and cancels its job if it runs; returns once no job of it runs,
  // so the caller may remove its folder.
  void cancel(const std::string& mapId);
  // Waits until the map is neither queued nor running, or `timeout` has passed: true if it is not.
  bool waitIdle(const std::string& mapId, std::chrono::milliseconds timeout);

  // Tests: `hook(mapId, cancelled)` runs on the compressor's thread as each job starts, before it
  // writes (a hook that waits must also end when `cancelled` says so: stop() waits for it).
  using Hook = std::function<void(const std::string& mapId, const std::function<bool()>& cancelled)>;
  void setBeforeJob(Hook hook);

 private:
  void run();

  Job job_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::string> queue_;
  std::string running_;       // the map whose job runs ("" for none)
  bool cancelRunning_ = false;
  bool stopping_ = false;
  Hook beforeJob_;
  std::thread thread_;  // started with the first job
};

}  // namespace rover::api
