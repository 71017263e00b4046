#pragma once
// The live state of one mission and its WebSocket subscribers (issue: server, "Live streams").
//
// The planner writes events into it (it is the planner's EventSink); each subscriber pulls frames
// with its own cursors — grid version, trail lengths, progress version — so a slow client costs a
// few integers, intermediate grid states coalesce into one diff, and the final state is never
// dropped: "done" is only handed out once the client has everything before it.
//
// Protocol (documented in README.md):
//   1. text   {"type":"snapshot", mission, status, grid{rows,cols,cell_size_m}|null, rovers[{trail,pose}], progress, metrics}
//   2. binary full grid (type 2), then diffs (type 1) as cells change
//   3. text   {"type":"poses", step, rovers[{rover, append[[x,y]...], pose{x,y,heading_deg}, believed?[[x,y]...]}]}
//             — a coverage mission under localisation error (issue 15): `append` and `pose` are the
//             true positions, `believed` appends to where the rover believes it has been; the
//             snapshot's rovers then carry "believed_trail" whole
//   4. text   {"type":"progress", ..., metrics?} and {"type":"status", status}
//      text   {"type":"overlay", route?[[x,y]...], paths[{rover, append[[x,y]...]}]} — the team
//             route (replaces the last) and each rover's planned path as it is accepted; the
//             snapshot carries both whole as "route" and "paths"
//   5. text   {"type":"done", status, message, metrics} — the last frame, then a normal close
// Binary frames, little-endian: u32 type, u32 rows, u32 cols, u32 count, then
//   type 1: count × (u32 cell index, u8 state, u8×3 zero, u32 visits)
//   type 2: rows·cols × u8 state, then rows·cols × u32 visits
//
// Memory (issue 14): the snapshot and the full grid frame are built once per state of the stream
// and shared, immutable, by every subscriber that joins at that state (a finished mission: one
// copy for all); the snapshot's JSON is formatted outside the lock the planner's events take.
// A queued mission's grid is allocated when the planner first reports cells.
//
// Fan-out (issue 22): what subscribers are sent is published in cuts, at most one every
// kCutEvery (taken on the planner's event that finds one due, then the subscribers are woken;
// the end of the mission and a joiner's snapshot cut at once). A subscriber always
// stands at a cut, and the frames from one cut to the newest (a batch: overlay, grid, poses,
// progress, status) are encoded once and shared by every subscriber standing at that cut; a
// subscriber that fell behind gets one coalesced batch from where it stands. A joiner reuses a
// snapshot up to kSnapshotReuse old (then catches up by a batch), so a crowd of joiners costs a
// few snapshots a second, not one each.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/grid/geometry.hpp"
#include "core/planning/events.hpp"
#include "server/http/http_types.hpp"
#include "server/store/run_status.hpp"

namespace rover::missions {

class MissionStream : public EventSink, public std::enable_shared_from_this<MissionStream> {
 public:
  // `grid` is the planner's cell grid (0×0 when the planner has none); `paceStepsPerSecond` > 0
  // slows the planner down to that many steps a second so people can watch (0 = full speed).
  MissionStream(std::string missionId, const GridGeometry& grid, int rovers,
                double paceStepsPerSecond = 0);

  // EventSink — called on the planner's thread.
  void cellsChanged(std::span<const CellUpdate> cells) override;
  void roverPoses(std::int64_t step, std::span<const RoverPose> poses) override;
  void progress(const Progress& p) override;
  void overlay(std::string_view kind, int rover, std::span<const Point2> points) override;
  void metrics(std::span<const Metric> metrics) override;

  void setStatus(RunStatus status);
  // The final frame's content; wakes every subscriber.
  void finish(RunStatus status, const std::string& message, const nlohmann::json& metrics);
  bool finished() const;
  // Called by the manager's thread, read by the planner's (pacing): atomic.
  void setCancelled() { cancelRequested_.store(true, std::memory_order_relaxed); }

  // Status, progress and (when finished) metrics, for GET /api/missions/{id}.
  nlohmann::json summary() const;
  // Final grid (type 2 frame bytes) and trails, for storing and replaying a finished mission.
  std::string fullGridFrame() const;
  nlohmann::json trailsJson() const;
  // {"route": [[x,y]...], "paths": [[[x,y]...] per rover]} — stored beside the trails.
  nlohmann::json overlaysJson() const;
  void restoreOverlays(const nlohmann::json& overlays);
  // [[[x,y]...] per rover] — the believed trails (localisation error), stored beside the trails.
  nlohmann::json beliefsJson() const;
  void restoreBeliefs(const nlohmann::json& beliefs);
  // Rebuilds a finished mission's stream from its stored grid frame and result.
  static std::shared_ptr<MissionStream> fromStored(const std::string& missionId,
                                                   const std::string& gridFrame,
                                                   const nlohmann::json& trails,
                                                   RunStatus status,
                                                   const std::string& message,
                                                   const nlohmann::json& metrics);

  std::shared_ptr<http::WsSource> subscribe(std::shared_ptr<http::WsConnection> connection);
  std::size_t subscriberCount() const;
  // How many snapshots (JSON + full grid) were built so far: one per state that clients joined at.
  std::uint64_t snapshotBuilds() const { return snapshotBuilds_.load(); }
  // How many frames after the snapshot were encoded so far (shared by the subscribers at a cut).
  std::uint64_t frameEncodes() const { return frameEncodes_.load(); }

  static constexpr std::chrono::milliseconds kCutEvery{15};
  static constexpr std::chrono::milliseconds kSnapshotReuse{250};

 private:
  class Subscription;
  struct Pose {
    float x, y, headingDeg;
  };
  // The stream at one cut, as the cursors of a subscriber standing there.
  struct Cursors {
    std::uint64_t cut = 0;    // the cut's number
    std::uint64_t state = 0;  // stateVersion_ at the cut
    std::uint64_t grid = 0, route = 0, progress = 0, status = 0;
    std::int64_t step = 0;
    std::vector<std::size_t> trails, beliefs, paths;  // lengths
  };
  using Batch = std::vector<http::WsFrame>;
  // What a joining client gets first, shared by all that join at the same state, with the
  // cursors it stands for.
  struct Snapshot {
    Cursors at;
    std::chrono::steady_clock::time_point builtAt;
    std::shared_ptr<const std::string> json, grid;  // grid null when the planner has none
  };
  std::shared_ptr<const Snapshot> snapshot();
  void wakeAll(bool force);
  // The newest cut becomes the current state; the progress and status frames are encoded there.
  void cutLocked();
  bool dirtyLocked() const { return stateVersion_ != head_.state; }
  // The frames that take a subscriber from `from` to head_ (caller holds mutex_).
  std::shared_ptr<const Batch> batchLocked(const Cursors& from);
  std::string gridDiffFrame(std::uint64_t since, std::uint64_t until) const;  // caller holds mutex_
  std::string fullGridFrameLocked() const;                 // caller holds mutex_
  // The full grid frame of the current grid version, built once and shared (caller holds mutex_).
  std::shared_ptr<const std::string> sharedFullGridLocked();
  std::uint64_t gridVersionLocked() const { return logBase_ + changeLog_.size(); }
  void allocateGridLocked();  // state_/visits_ on first use

  const std::string id_;
  const GridGeometry grid_;
  const double pace_;
  std::atomic<bool> cancelRequested_{false};
  std::chrono::steady_clock::time_point paceStart_{};
  std::int64_t paceFirstStep_ = -1;

  mutable std::mutex mutex_;
  std::vector<std::uint8_t> state_;
  std::vector<std::uint32_t> visits_;
  std::vector<std::int32_t> changeLog_;  // cell indices in change order
  std::uint64_t logBase_ = 0;            // version of changeLog_[0]
  std::vector<std::vector<Pose>> trails_;
  std::vector<std::vector<std::array<float, 2>>> beliefs_;  // believed trails; empty when none
  std::vector<std::array<float, 2>> route_;
  std::uint64_t routeVersion_ = 0;
  std::vector<std::vector<std::array<float, 2>>> paths_;
  std::int64_t step_ = 0;
  nlohmann::json progress_ = nullptr;
  std::uint64_t progressVersion_ = 0;
  RunStatus status_ = RunStatus::Queued;
  std::uint64_t statusVersion_ = 0;
  bool finished_ = false;
  std::string message_;
  nlohmann::json metrics_ = nullptr;
  nlohmann::json liveMetrics_ = nullptr;  // from the planner's metrics event, before the end
  std::vector<std::weak_ptr<http::WsConnection>> subscribers_;
  std::uint64_t stateVersion_ = 0;  // bumped by every change a snapshot shows
  std::shared_ptr<const Snapshot> snapshot_;
  std::shared_ptr<const std::string> fullGrid_;  // of fullGridVersion_
  std::uint64_t fullGridVersion_ = ~0ull;
  std::mutex snapshotBuildMutex_;  // one builder at a time; the others then share its snapshot
  std::atomic<std::uint64_t> snapshotBuilds_{0};
  Cursors head_;  // the newest cut
  std::chrono::steady_clock::time_point headAt_{};
  std::map<std::uint64_t, std::shared_ptr<const Batch>> batches_;  // by the cut they start from
  std::shared_ptr<const std::string> progressFrame_, statusFrame_, doneFrame_;  // as of head_
  mutable std::vector<std::uint8_t> diffSeen_;  // scratch of gridDiffFrame, all zero between calls
  std::atomic<std::uint64_t> frameEncodes_{0};
};

}  // namespace rover::missions
