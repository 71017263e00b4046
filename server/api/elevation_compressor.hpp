#pragma once
// The background writer of stored maps' COGs (issue 24): an import announces its map with the
// elevation raw (server/api/map_files.hpp kRawDemDir) and queues it here; one thread then writes
// each map's dem.tif in turn, in the order queued. One job at a time, so memory is one COG
// write's (GDAL's block cache, capped at GDAL_CACHEMAX, 256 MiB by default, plus the COG driver's
// buffers: a few 256-row strips), whatever the number of maps waiting.
// A job that fails (a full disk or disk budget, a transient error) is tried again while the
// server runs, after a growing wait and a bounded number of times (kAttempts); the map stays raw
// and readable meanwhile and after, and the next start queues it again.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>

namespace rover::api {

class ElevationCompressor {
 public:
  // `job(mapId, cancelled)` writes one map's COG; it polls `cancelled` while it works and stops
  // when it says so. Its exceptions are its own to report (they are logged here, not rethrown);
  // one thrown when not cancelled is a failure, tried again (below).
  using Job = std::function<void(const std::string& mapId, const std::function<bool()>& cancelled)>;
  explicit ElevationCompressor(Job job);
  // Cancels the running job, drops the queue and the retries and joins the thread (a map left raw
  // is queued again at the next start).
  ~ElevationCompressor();
  ElevationCompressor(const ElevationCompressor&) = delete;
  ElevationCompressor& operator=(const ElevationCompressor&) = delete;

  // What the destructor does, earlier: for an owner whose callbacks die before the compressor.
  void stop();

  // Queues the map (once: a map already queued, running or waiting for a retry is not queued
  // again; one whose retries were all used is queued afresh, its failures forgotten).
  void enqueue(const std::string& mapId);
  // Drops the map from the queue and its retry, and cancels its job if it runs; returns once no
  // job of it runs, so the caller may remove its folder. A map waiting for a retry runs no job:
  // this returns at once.
  void cancel(const std::string& mapId);
  // Waits until the map is neither queued, running nor waiting for a retry, or `timeout` has
  // passed: true if it is not.
  bool waitIdle(const std::string& mapId, std::chrono::milliseconds timeout);

  // Retries: at most kAttempts jobs of a map in all (the first and 7 retries); the retry after
  // the n-th failure comes retryDelay(n) later: 1, 2, 4, 8, 16, 30, 30 min (doubling from
  // kFirstRetryDelay, at most kMaxRetryDelay), so the last is about 1.5 h after the first
  // failure. A full disk or budget often clears within that (a map or missions deleted); if not,
  // the map stays raw until the next start. Between retries the thread sleeps on a condition
  // variable until the earliest one is due (never a poll), and delete, stop and new maps wake it.
  using Clock = std::chrono::steady_clock;
  static constexpr int kAttempts = 8;
  static constexpr std::chrono::minutes kFirstRetryDelay{1};
  static constexpr std::chrono::minutes kMaxRetryDelay{30};
  static Clock::duration retryDelay(int failures);

  // Where a map is (for tests and logs).
  enum class State { Idle, Queued, Running, WaitingRetry, GaveUp };
  struct Status {
    State state = State::Idle;
    int failures = 0;          // failed jobs since it was queued
    Clock::time_point retryAt;  // WaitingRetry: when its next job is due (on the clock below)
  };
  Status status(const std::string& mapId);

  // Tests: `hook(mapId, cancelled)` runs on the compressor's thread as each job starts, before it
  // writes (a hook that waits must also end when `cancelled` says so: stop() waits for it). A
  // hook that throws fails the job, as the job's own exception would.
  using Hook = std::function<void(const std::string& mapId, const std::function<bool()>& cancelled)>;
  void setBeforeJob(Hook hook);
  // Tests: the clock retries are timed by (Clock::now by default), so a test moves time instead
  // of waiting; wake() after moving it makes the thread look at it again. `now` is called with
  // the compressor's lock held: it must not call back into it.
  void setClock(std::function<Clock::time_point()> now);
  void wake();

 private:
  void run();
  // Moves the retries that are due to the queue's back.
  void queueDueRetriesLocked();

  Job job_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::string> queue_;
  std::string running_;       // the map whose job runs ("" for none)
  bool cancelRunning_ = false;
  bool stopping_ = false;
  Hook beforeJob_;
  std::function<Clock::time_point()> now_;
  std::map<std::string, int> failures_;               // maps that failed, until done or cancelled
  std::map<std::string, Clock::time_point> retryAt_;  // maps waiting for a retry
  std::thread thread_;  // started with the first job
};

}  // namespace rover::api
