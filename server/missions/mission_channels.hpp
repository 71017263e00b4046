#pragma once
// The channels of a mission's stream (MissionStream): what the planner reports, each kept as the
// log a subscriber reads from its position, and the frames that take a reader from one position
// to another (formats in mission_stream.hpp). Every member is guarded by the stream's mutex.
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/grid/geometry.hpp"
#include "core/planning/events.hpp"
#include "server/store/run_status.hpp"
#include "server/streams/channel_stream.hpp"

namespace rover::missions {

using streams::Batch;
using streams::Position;
using XY = std::array<float, 2>;

// The team route (replaced whole: position = its version) and each rover's planned path
// (appended: position = its length).
class OverlayChannel : public streams::Channel {
 public:
  OverlayChannel() : Channel("overlay") {}
  void add(std::string_view kind, int rover, std::span<const Point2> points);
  nlohmann::json json() const;  // {"route", "paths"}
  void restore(const nlohmann::json& overlays);
  bool empty() const { return route_.empty() && paths_.empty(); }
  const std::vector<XY>& route() const { return route_; }
  const std::vector<std::vector<XY>>& paths() const { return paths_; }
  Position position() const override;
  std::size_t frames(const Position& from, const Position& to, Batch& out) override;

 private:
  std::vector<XY> route_;
  std::uint64_t routeVersion_ = 0;
  std::vector<std::vector<XY>> paths_;
};

// The cell grid: state and visits of every cell, and the log of changed cells a diff is made
// from. The log is the channel's bounded replay: past 2 × cells (+1024) it is compacted, and a
// reader behind a compaction gets the full grid.
class GridChannel : public streams::Channel {
 public:
  explicit GridChannel(const GridGeometry& grid) : Channel("grid"), grid_(grid) {}
  const GridGeometry& geometry() const { return grid_; }
  bool present() const { return grid_.cellCount() > 0; }
  void apply(std::span<const CellUpdate> cells);
  // The geometry a stored full-grid frame is of (0×0 when it is not one), and its cells.
  static GridGeometry geometryOf(const std::string& fullFrame);
  void restore(const std::string& fullFrame);
  std::string fullFrame() const;
  // The full grid frame of the current version, built once and shared.
  std::shared_ptr<const std::string> sharedFullFrame();
  Position position() const override { return {version()}; }
  std::size_t frames(const Position& from, const Position& to, Batch& out) override;

 private:
  std::uint64_t version() const { return logBase_ + changeLog_.size(); }
  void allocate();  // state_/visits_ on first use: a queued mission holds no grid
  std::string diffFrame(std::uint64_t since, std::uint64_t until) const;

  const GridGeometry grid_;
  std::vector<std::uint8_t> state_;
  std::vector<std::uint32_t> visits_;
  std::vector<std::int32_t> changeLog_;  // cell indices in change order
  std::uint64_t logBase_ = 0;            // version of changeLog_[0]
  std::shared_ptr<const std::string> full_;  // of fullVersion_
  std::uint64_t fullVersion_ = ~0ull;
  mutable std::vector<std::uint8_t> diffSeen_;  // scratch of diffFrame, all zero between calls
};

// The rovers' trails (true positions, with the heading of the last), the believed trails of a
// mission under localisation error, and the step. Position: step, then per rover its trail's
// and its believed trail's lengths.
class PosesChannel : public streams::Channel {
 public:
  struct Pose {
    float x, y, headingDeg;
  };
  explicit PosesChannel(int rovers) : Channel("poses"), trails_(std::max(0, rovers)) {}
  void apply(std::int64_t step, std::span<const RoverPose> poses);
  std::int64_t step() const { return step_; }
  const std::vector<std::vector<Pose>>& trails() const { return trails_; }
  const std::vector<std::vector<XY>>& beliefs() const { return beliefs_; }
  void addStoredPoint(std::size_t rover, Pose p) { trails_[rover].push_back(p); }
  nlohmann::json trailsJson() const;
  nlohmann::json beliefsJson() const { return beliefs_; }
  void restoreBeliefs(const nlohmann::json& beliefs);
  Position position() const override;
  std::size_t frames(const Position& from, const Position& to, Batch& out) override;

 private:
  std::vector<std::vector<Pose>> trails_;
  std::vector<std::vector<XY>> beliefs_;  // empty when none
  std::int64_t step_ = 0;
};

// The incidents found so far (issue 27: streamed as they are found), appended as the planner
// reports them, then replaced by the run's complete list (the same as result.json's). Position:
// how many times the list was replaced, then its length. Frame: {"type":"incidents", from,
// complete, incidents[...]}: a reader keeps its first `from` incidents and appends these.
// Memory: one JSON object per incident, as many as the result lists.
class IncidentChannel : public streams::Channel {
 public:
  IncidentChannel() : Channel("incidents") {}
  void add(std::span<const Incident> found, bool complete);
  const nlohmann::json& items() const { return items_; }
  bool complete() const { return complete_; }
  Position position() const override { return {replaced_, items_.size()}; }
  std::size_t frames(const Position& from, const Position& to, Batch& out) override;

 private:
  nlohmann::json items_ = nlohmann::json::array();
  std::uint64_t replaced_ = 0;
  bool complete_ = false;
};

// A value overwritten in place, sent whole when it changed: its frame is encoded at the cut
// (position = its version).
class ValueChannel : public streams::Channel {
 public:
  using Channel::Channel;
  void changed() { ++version_; }
  Position position() const override { return {version_}; }
  std::size_t cut(const Position& from, const Position& to) override;
  std::size_t frames(const Position& from, const Position& to, Batch& out) override;

 protected:
  virtual nlohmann::json frameJson() const = 0;
  virtual bool silent() const { return false; }  // sends nothing (a later frame carries it)

 private:
  std::uint64_t version_ = 0;
  std::shared_ptr<const std::string> frame_;  // as of the newest cut
};

// The planner's progress and its live metrics: {"type":"progress", ..., metrics?}.
class ProgressChannel : public ValueChannel {
 public:
  ProgressChannel() : ValueChannel("progress") {}
  void set(const Progress& p);
  void setMetrics(std::span<const Metric> metrics);
  const nlohmann::json& progress() const { return progress_; }

 private:
  nlohmann::json frameJson() const override;
  nlohmann::json progress_ = nullptr;
  nlohmann::json liveMetrics_ = nullptr;  // from the planner's metrics event, before the end
};

// The mission's status, and its end: {"type":"status", status} until the end, whose done frame
// carries the status instead.
class StatusChannel : public ValueChannel {
 public:
  StatusChannel() : ValueChannel("status") {}
  void set(RunStatus status);
  void finish(RunStatus status, const std::string& message, const nlohmann::json& metrics);
  RunStatus status() const { return status_; }
  const std::string& message() const { return message_; }
  const nlohmann::json& metrics() const { return metrics_; }
  bool finished() const { return finished_; }

 private:
  nlohmann::json frameJson() const override { return {{"type", "status"}, {"status", enumName(status_)}}; }
  bool silent() const override { return finished_; }
  RunStatus status_ = RunStatus::Queued;
  std::string message_;
  nlohmann::json metrics_ = nullptr;
  bool finished_ = false;
};

nlohmann::json poseJson(float x, float y, float headingDeg);

}  // namespace rover::missions
