#pragma once
// The live state of one mission and its WebSocket subscribers (issue: server, "Live streams").
//
// The planner writes events into it (it is the planner's EventSink); each subscriber pulls frames
// with its own cursors — grid version, trail lengths, progress version — so a slow client costs a
// few integers, intermediate grid states coalesce into one diff, and the final state is never
// dropped: "done" is only handed out once the client has everything before it.
//
// Protocol (documented in README.md):
//   1. text   {"type":"snapshot", mission, status, grid{rows,cols,cell_size_m,origin}|null, rovers[{trail,pose}], progress, metrics}
//             — grid.origin [x, y]: where the grid's lower-left corner lies in the map's local
//             frame ([0, 0] but for a mission in an area: its planning window's origin, issue 24)
//   2. binary full grid (type 2), then diffs (type 1) as cells change
//   3. text   {"type":"poses", step, rovers[{rover, append[[x,y]...], pose{x,y,heading_deg}, believed?[[x,y]...]}]}
//             — a coverage mission under localisation error (issue 15): `append` and `pose` are the
//             true positions, `believed` appends to where the rover believes it has been; the
//             snapshot's rovers then carry "believed_trail" whole
//   4. text   {"type":"progress", ..., metrics?} and {"type":"status", status}
//      text   {"type":"overlay", route?[[x,y]...], paths[{rover, append[[x,y]...]}]} — the team
//             route (replaces the last) and each rover's planned path as it is accepted; the
//             snapshot carries both whole as "route" and "paths"
//      text   {"type":"incidents", from, complete, incidents[...]} — incidents as the planner finds
//             them (result.json's shape, issue 27): keep the first `from` already held, append
//             these; `complete`: the run's whole list (as result.json's) has been sent. The
//             snapshot carries the list so far as "incidents" (and "incidents_complete")
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
// Fan-out (issue 22): a ChannelStream (server/streams/channel_stream.hpp) of six channels,
// whose frames make a batch in this order: overlay, grid, poses, incidents, progress, status
// (mission_channels.hpp). What subscribers are sent is published in cuts, at most one every
// kCutEvery (taken on the planner's event that finds one due, then the subscribers are woken;
// the end of the mission and a joiner's snapshot cut at once); a subscriber that fell behind gets
// one coalesced batch from where it stands. A joiner reuses a snapshot up to kSnapshotReuse old
// (then catches up by a batch), so a crowd of joiners costs a few snapshots a second, not one each.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "core/grid/geometry.hpp"
#include "core/planning/events.hpp"
#include "server/missions/mission_channels.hpp"
#include "server/streams/channel_stream.hpp"

namespace rover::missions {

class MissionStream : public EventSink, public streams::ChannelStream {
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
  void incidents(std::span<const Incident> found, bool complete) override;

  // Where the planner's grid lies on the map (its lower-left corner, local frame); set before the
  // stream is shared (submit, or a replay from disk).
  void setGridOrigin(const Eigen::Vector2d& origin) { gridOrigin_ = origin; }

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

  static constexpr std::chrono::milliseconds kCutEvery{15};
  static constexpr std::chrono::milliseconds kSnapshotReuse{250};

 private:
  std::function<streams::Batch()> captureSnapshotLocked() override;
  bool endedLocked() const override { return status_.finished(); }
  std::shared_ptr<const std::string> doneFrameLocked() override;

  const std::string id_;
  const double pace_;
  std::atomic<bool> cancelRequested_{false};
  std::chrono::steady_clock::time_point paceStart_{};
  std::int64_t paceFirstStep_ = -1;

  // The channels, guarded by mutex_.
  OverlayChannel overlay_;
  GridChannel grid_;
  PosesChannel poses_;
  IncidentChannel incidents_;
  ProgressChannel progress_;
  StatusChannel status_;
  std::shared_ptr<const std::string> doneFrame_;
  Eigen::Vector2d gridOrigin_{0, 0};
};

}  // namespace rover::missions
