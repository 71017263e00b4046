#include "server/missions/mission_stream.hpp"

#include <thread>

namespace rover::missions {

MissionStream::MissionStream(std::string missionId, const GridGeometry& grid, int rovers,
                             double paceStepsPerSecond)
    : ChannelStream({kCutEvery, kSnapshotReuse, std::chrono::milliseconds(30)}),
      id_(std::move(missionId)),
      pace_(paceStepsPerSecond),
      grid_(grid),
      poses_(rovers) {
  for (streams::Channel* c : std::initializer_list<streams::Channel*>{&overlay_, &grid_, &poses_, &incidents_, &progress_, &status_})
    addChannel(*c);
}

std::function<streams::Batch()> MissionStream::captureSnapshotLocked() {
  // Under the stream's lock only copies of the compact state (12 bytes a trail point) and the
  // shared grid frame; the JSON, several times bigger, is formatted after the lock is released.
  std::shared_ptr<const std::string> gridFrame;
  nlohmann::json grid = nullptr;
  if (grid_.present()) {
    gridFrame = grid_.sharedFullFrame();
    const GridGeometry& g = grid_.geometry();
    grid = {{"rows", g.rows}, {"cols", g.cols}, {"cell_size_m", g.cellWidth},
            {"origin", {gridOrigin_.x(), gridOrigin_.y()}}};
  }
  nlohmann::json j = {{"type", "snapshot"}, {"mission", id_},          {"status", enumName(status_.status())},
                      {"grid", grid},       {"rovers", nullptr},       {"step", poses_.step()},
                      {"progress", progress_.progress()}, {"metrics", status_.metrics()}};
  j["incidents"] = incidents_.items();
  j["incidents_complete"] = incidents_.complete();
  if (!overlay_.empty()) {
    j["route"] = overlay_.route();
    j["paths"] = overlay_.paths();
  }
  return [j = std::move(j), gridFrame, trails = poses_.trails(), beliefs = poses_.beliefs()]() mutable {
    // The rovers' trails are formatted one rover at a time into the text (not one JSON tree of
    // every point) and spliced where the placeholder is; the keys keep nlohmann's sorted order.
    std::string rovers = "[";
    for (std::size_t k = 0; k < trails.size(); ++k) {
      nlohmann::json trail = nlohmann::json::array();
      for (const auto& p : trails[k]) trail.push_back({p.x, p.y});
      nlohmann::json r{{"rover", k}, {"trail", std::move(trail)}, {"pose", nullptr}};
      if (!trails[k].empty()) {
        const PosesChannel::Pose& p = trails[k].back();
        r["pose"] = poseJson(p.x, p.y, p.headingDeg);
      }
      if (k < beliefs.size()) {
        r["believed_trail"] = beliefs[k];
        std::vector<XY>().swap(beliefs[k]);
      }
      if (k > 0) rovers += ',';
      rovers += r.dump();
      std::vector<PosesChannel::Pose>().swap(trails[k]);
    }
    rovers += ']';
    std::string text = j.dump();
    const std::string placeholder = "\"rovers\":null";
    // The last occurrence: keys are sorted and only "status", "step" and "type" (no such text)
    // follow the top-level "rovers"; a NaN metric named "rovers" would come earlier.
    const auto at = text.rfind(placeholder);
    text.replace(at, placeholder.size(), "\"rovers\":" + rovers);
    streams::Batch frames{http::WsFrame{false, std::make_shared<const std::string>(std::move(text)), false}};
    if (gridFrame) frames.emplace_back(true, std::move(gridFrame), false);
    return frames;
  };
}

std::shared_ptr<const std::string> MissionStream::doneFrameLocked() {
  if (!doneFrame_) {
    doneFrame_ = std::make_shared<const std::string>(
        nlohmann::json{{"type", "done"}, {"mission", id_}, {"status", enumName(status_.status())}, {"message", status_.message()},
                       {"metrics", status_.metrics()}, {"step", poses_.step()}}
            .dump());
    countEncodes(1);
  }
  return doneFrame_;
}

void MissionStream::cellsChanged(std::span<const CellUpdate> cells) {
  {
    std::lock_guard lock(mutex_);
    grid_.apply(cells);
    changedLocked();
  }
  wakeAll(false);
}

void MissionStream::roverPoses(std::int64_t step, std::span<const RoverPose> poses) {
  {
    std::lock_guard lock(mutex_);
    poses_.apply(step, poses);
    changedLocked();
  }
  wakeAll(false);
  if (pace_ > 0 && !cancelRequested_.load(std::memory_order_relaxed)) {
    // Hold the planner to `pace_` steps a second so a person can watch; short sleeps keep
    // cancellation prompt (the planner checks its token every step).
    auto now = std::chrono::steady_clock::now();
    if (paceFirstStep_ < 0) paceFirstStep_ = step, paceStart_ = now;
    auto due = paceStart_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>((step - paceFirstStep_) / pace_));
    if (due > now) std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(due - now, std::chrono::milliseconds(50)));
  }
}

void MissionStream::progress(const Progress& p) {
  {
    std::lock_guard lock(mutex_);
    progress_.set(p);
    changedLocked();
  }
  wakeAll(false);
}

void MissionStream::overlay(std::string_view kind, int rover, std::span<const Point2> points) {
  {
    std::lock_guard lock(mutex_);
    changedLocked();
    overlay_.add(kind, rover, points);
  }
  wakeAll(false);
}

void MissionStream::metrics(std::span<const Metric> metrics) {
  {
    std::lock_guard lock(mutex_);
    progress_.setMetrics(metrics);
    changedLocked();
  }
  wakeAll(false);
}

void MissionStream::incidents(std::span<const Incident> found, bool complete) {
  {
    std::lock_guard lock(mutex_);
    incidents_.add(found, complete);
    changedLocked();
  }
  wakeAll(false);
}

nlohmann::json MissionStream::overlaysJson() const {
  std::lock_guard lock(mutex_);
  return overlay_.json();
}

void MissionStream::restoreOverlays(const nlohmann::json& o) {
  std::lock_guard lock(mutex_);
  if (!o.is_object()) return;
  changedLocked();
  overlay_.restore(o);
}

nlohmann::json MissionStream::beliefsJson() const {
  std::lock_guard lock(mutex_);
  return poses_.beliefsJson();
}

void MissionStream::restoreBeliefs(const nlohmann::json& b) {
  std::lock_guard lock(mutex_);
  if (!b.is_array() || b.size() > 4096) return;
  changedLocked();
  poses_.restoreBeliefs(b);
}

void MissionStream::setStatus(RunStatus status) {
  {
    std::lock_guard lock(mutex_);
    status_.set(status);
    changedLocked();
  }
  wakeAll(true);
}

void MissionStream::finish(RunStatus status, const std::string& message,
                           const nlohmann::json& metrics) {
  {
    std::lock_guard lock(mutex_);
    status_.finish(status, message, metrics);
    changedLocked();
  }
  wakeAll(true);
}

bool MissionStream::finished() const {
  std::lock_guard lock(mutex_);
  return status_.finished();
}

nlohmann::json MissionStream::summary() const {
  std::lock_guard lock(mutex_);
  return {{"status", enumName(status_.status())}, {"step", poses_.step()},       {"progress", progress_.progress()},
          {"metrics", status_.metrics()}, {"message", status_.message()}, {"subscribers", subscriberSlotsLocked()}};
}

std::string MissionStream::fullGridFrame() const {
  std::lock_guard lock(mutex_);
  return grid_.fullFrame();
}

nlohmann::json MissionStream::trailsJson() const {
  std::lock_guard lock(mutex_);
  return poses_.trailsJson();
}

std::shared_ptr<MissionStream> MissionStream::fromStored(const std::string& missionId,
                                                         const std::string& gridFrame,
                                                         const nlohmann::json& trails,
                                                         RunStatus status,
                                                         const std::string& message,
                                                         const nlohmann::json& metrics) {
  const GridGeometry g = GridChannel::geometryOf(gridFrame);
  auto s = std::make_shared<MissionStream>(missionId, g, static_cast<int>(trails.size()));
  s->grid_.restore(gridFrame);  // not shared yet: no lock needed
  for (std::size_t k = 0; k < trails.size(); ++k)
    for (const auto& p : trails[k])
      s->poses_.addStoredPoint(k, {p.at(0).get<float>(), p.at(1).get<float>(), p.size() > 2 ? p.at(2).get<float>() : 0.0f});
  s->finish(status, message, metrics);
  return s;
}

}  // namespace rover::missions
