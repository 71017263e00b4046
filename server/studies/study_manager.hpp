#pragma once
// The server's studies (issue 12): POST /api/studies queues a study, one runs at a time, below the
// missions in priority, and a restart resumes what was unfinished. Built on the engine's public
// interface (studies.hpp); nothing here plans.
//
// Where a study lives: DATA/studies/ID/ holds spec.json (the study document as accepted),
// state.json (status, times, message: rewritten atomically at each change), study.sqlite (the
// engine's study database), runs.csv (the last download) and, with a launcher, launcher.log.
// Never a client-chosen path: the id is the server's (DataDir::newId), and specs naming DEM files
// are refused.
//
// Priority: a study runs on one thread of its own, one run at a time, and takes its next run only
// when no mission is waiting and the missions leave a core free (`missionsBusy`), so a mission
// never waits behind a study; a run in flight is not preempted (runs of the presets take
// milliseconds to a few seconds).
// With a launcher (`serve --study-launcher "mpirun -np 16 --hostfile H"`) the study runs as that
// command + `roverplan study run --spec spec.json --out study.sqlite --quiet`, a child process
// started without a shell; its progress is read from the database the child writes.
//
// Bounds (stated in README "Studies"): kMaxServerRuns runs per study, kMaxActive studies queued or
// running, kMaxStored studies kept; one study runs at a time.
#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/cancel.hpp"
#include "server/http/http_types.hpp"
#include "server/store/data_dir.hpp"

namespace rover::studies {

constexpr std::size_t kMaxServerRuns = 200'000;  // runs (configurations × runs) of one study
constexpr std::size_t kMaxActive = 4;            // studies queued or running
constexpr std::size_t kMaxStored = 100;          // studies kept (delete ended ones for room)

// A launcher string split into argv the way a shell splits words, without a shell: blanks
// separate, '…' and "…" quote, a backslash escapes the next character. Throws on an open quote.
std::vector<std::string> splitCommandLine(const std::string& line);

struct StudyState {
  std::string id, name;
  std::string status = "queued";  // queued | running | succeeded | cancelled | failed
  std::string message;
  std::string createdAt, startedAt, finishedAt;
  std::size_t done = 0, total = 0;
  double etaSeconds = -1;   // -1 = not known yet
  double runsPerSecond = 0;
  bool cancelRequested = false;
};
nlohmann::json toJson(const StudyState& s);
bool isEnded(const std::string& status);

// The live state of one study and its WebSocket subscribers, in the pull model of the mission
// streams (MissionStream): each subscriber keeps a version cursor, so a slow client costs two
// integers and intermediate states coalesce. Frames (text):
//   {"type":"snapshot", study{...state}, summary}           first
//   {"type":"progress", done, total, eta_s, runs_per_s, status, summary?}  summary: when it changed
//   {"type":"done", status, message, done, total, summary}  last, then a normal close
// Each frame is encoded once per version and shared by every subscriber (issue 22): a crowd of
// readers costs the study thread nothing but the wake-ups.
class StudyStream : public std::enable_shared_from_this<StudyStream> {
 public:
  void update(const StudyState& state);                 // progress / status
  void setSummary(nlohmann::json summary);              // the partial (or final) summary
  std::shared_ptr<http::WsSource> subscribe(std::shared_ptr<http::WsConnection> connection);

 private:
  class Subscription;
  void wakeAll();
  mutable std::mutex mutex_;
  StudyState state_;
  nlohmann::json summary_ = nullptr;
  std::uint64_t version_ = 0, summaryVersion_ = 0;
  std::vector<std::weak_ptr<http::WsConnection>> subscribers_;
  // Encoded frames and the versions they are of (caller holds mutex_).
  struct Encoded {
    std::uint64_t version = ~0ull, summaryVersion = ~0ull;
    std::shared_ptr<const std::string> bytes;
  };
  Encoded snapshot_, progress_, progressWithSummary_, done_;
  std::shared_ptr<const std::string> encodedLocked(Encoded& slot, bool withSummary,
                                                   const std::function<nlohmann::json()>& make) const;
  mutable std::uint64_t encodes_ = 0;

 public:
  std::uint64_t frameEncodes() const;  // frames encoded so far (shared by every subscriber)
};

class StudyManager {
 public:
  // `missionsBusy`: true while missions should have the machine (a mission waits, or they use
  // every core). `launcher`: empty = in-process; else argv prefix of the study command. `selfExe`:
  // the roverplan binary the launcher runs.
  StudyManager(store::DataDir& dir, std::function<bool()> missionsBusy,
               std::vector<std::string> launcher = {}, std::string selfExe = "/proc/self/exe");
  ~StudyManager();  // stop()

  // Validates (throws rover::Error naming the field, DomainError for the document and the bounds),
  // stores and queues a study document; returns its state.
  StudyState submit(const nlohmann::json& spec);
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
  std::string databasePath(const std::string& id) const;  // empty when there is none yet
  std::shared_ptr<StudyStream> stream(const std::string& id) const;

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
  void publishSummary(const std::string& id, const nlohmann::json& summary);
  nlohmann::json storedSummary(const std::string& id) const;  // summary.json, else the database's
  std::string folder(const std::string& id) const;
  void saveState(const StudyState& s) const;  // caller holds no lock; best effort on a full disk
  void loadStored();                          // start-up: every stored study; unfinished ones queued
  void work();
  void runInProcess(const std::string& id, const CancelToken& cancel);
  void runLaunched(const std::string& id, const CancelToken& cancel);
  // Progress: done/total, rate over this session, ETA; pushes the summary every few seconds.
  void report(const std::string& id, std::size_t done, std::size_t total, std::size_t doneAtStart,
              std::chrono::steady_clock::time_point start, const std::function<nlohmann::json()>& summary,
              std::chrono::steady_clock::time_point& lastSummary);
  void finish(const std::string& id, const std::string& status, const std::string& message);
  // Charges the study's folder (its database as it grew) to the global disk budget; throws
  // store::OverBudget past it.
  void chargeDisk(const std::string& id) const;

  store::DataDir& dir_;
  std::function<bool()> missionsBusy_;
  std::vector<std::string> launcher_;
  std::string selfExe_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::map<std::string, Entry> studies_;
  std::deque<std::string> queue_;
  bool stopping_ = false;
  std::thread worker_;  // last: started once the rest is constructed
};

}  // namespace rover::studies
