#include "server/missions/mission_stream.hpp"

#include <cmath>
#include <cstring>
#include <numbers>
#include <thread>

namespace rover::missions {

namespace {

constexpr std::uint32_t kCellUpdates = 1, kFullGrid = 2;

void putU32(std::string& out, std::uint32_t v) {
  char b[4] = {static_cast<char>(v & 0xff), static_cast<char>((v >> 8) & 0xff),
               static_cast<char>((v >> 16) & 0xff), static_cast<char>((v >> 24) & 0xff)};
  out.append(b, 4);
}
std::uint32_t getU32(const std::string& in, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(in[at + k]);
  return v;
}

nlohmann::json poseJson(float x, float y, float headingDeg) {
  return {{"x", x}, {"y", y}, {"heading_deg", headingDeg}};
}

}  // namespace

// One WebSocket client's place in the stream: the cut it stands at, and the shared batch it is
// sending.
class MissionStream::Subscription : public http::WsSource {
 public:
  explicit Subscription(std::shared_ptr<MissionStream> s) : stream_(std::move(s)) {}

  std::optional<http::WsFrame> next() override {
    MissionStream& s = *stream_;
    if (!snapshotSent_) {
      // Built (or reused) outside the stream's lock; the cursors are those of its cut.
      std::shared_ptr<const Snapshot> snap = s.snapshot();
      snapshotSent_ = true;
      at_ = snap->at;
      pendingGrid_ = snap->grid;
      return http::WsFrame{false, snap->json, false};
    }
    if (pendingGrid_) return http::WsFrame{true, std::move(pendingGrid_), false};
    if (batch_ && sent_ < batch_->size()) return (*batch_)[sent_++];
    batch_.reset();

    std::lock_guard lock(s.mutex_);
    if (s.finished_ && s.dirtyLocked()) s.cutLocked();  // the end is published whole
    if (at_.cut != s.head_.cut) {
      std::shared_ptr<const Batch>& b = s.batches_[at_.cut];
      if (!b) b = s.batchLocked(at_);
      at_ = s.head_;
      batch_ = b;
      sent_ = 0;
      if (!batch_->empty()) return (*batch_)[sent_++];
    }
    if (s.finished_ && !doneSent_) {
      doneSent_ = true;
      if (!s.doneFrame_) {
        s.doneFrame_ = std::make_shared<const std::string>(
            nlohmann::json{{"type", "done"}, {"mission", s.id_}, {"status", enumName(s.status_)}, {"message", s.message_},
                           {"metrics", s.metrics_}, {"step", s.step_}}
                .dump());
        ++s.frameEncodes_;
      }
      return http::WsFrame{false, s.doneFrame_, true};
    }
    return std::nullopt;
  }

 private:
  std::shared_ptr<MissionStream> stream_;
  bool snapshotSent_ = false, doneSent_ = false;
  Cursors at_;
  std::shared_ptr<const std::string> pendingGrid_;  // the snapshot's grid, sent right after it
  std::shared_ptr<const Batch> batch_;              // shared with the others at the same cut
  std::size_t sent_ = 0;                            // frames of batch_ sent
};

MissionStream::MissionStream(std::string missionId, const GridGeometry& grid, int rovers,
                             double paceStepsPerSecond)
    : id_(std::move(missionId)),
      grid_(grid),
      pace_(paceStepsPerSecond),
      trails_(std::max(0, rovers)) {}

void MissionStream::allocateGridLocked() {
  if (!state_.empty() || grid_.cellCount() <= 0) return;
  state_.assign(grid_.cellCount(), 0);
  visits_.assign(grid_.cellCount(), 0);
}

std::shared_ptr<const std::string> MissionStream::sharedFullGridLocked() {
  const std::uint64_t v = gridVersionLocked();
  if (!fullGrid_ || fullGridVersion_ != v) {
    fullGrid_ = std::make_shared<const std::string>(fullGridFrameLocked());
    fullGridVersion_ = v;
  }
  return fullGrid_;
}

std::shared_ptr<const MissionStream::Snapshot> MissionStream::snapshot() {
  std::lock_guard build(snapshotBuildMutex_);
  auto snap = std::make_shared<Snapshot>();
  // Under the stream's lock only copies of the compact state (12 bytes a trail point) and the
  // shared grid frame; the JSON, several times bigger, is formatted after the lock is released.
  std::vector<std::vector<Pose>> trails;
  std::vector<std::vector<std::array<float, 2>>> beliefs;
  nlohmann::json j;
  {
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    // The newest state, or one young enough: the joiner catches up from its cut by one batch.
    if (snapshot_ && ((snapshot_->at.cut == head_.cut && !dirtyLocked()) ||
                      (!finished_ && now - snapshot_->builtAt < kSnapshotReuse)))
      return snapshot_;
    if (dirtyLocked()) cutLocked();  // the snapshot stands at a cut, as every subscriber does
    snap->at = head_;
    snap->builtAt = now;
    beliefs = beliefs_;
    trails = trails_;
    if (grid_.cellCount() > 0) snap->grid = sharedFullGridLocked();
    nlohmann::json grid = nullptr;
    if (grid_.cellCount() > 0)
      grid = {{"rows", grid_.rows}, {"cols", grid_.cols}, {"cell_size_m", grid_.cellWidth}};
    j = {{"type", "snapshot"}, {"mission", id_},     {"status", enumName(status_)},  {"grid", grid},
         {"rovers", nullptr},  {"step", step_},      {"progress", progress_}, {"metrics", metrics_}};
    if (!route_.empty() || !paths_.empty()) {
      j["route"] = route_;
      j["paths"] = paths_;
    }
  }
  // The rovers' trails are formatted one rover at a time into the text (not one JSON tree of
  // every point) and spliced where the placeholder is; the keys keep nlohmann's sorted order.
  std::string rovers = "[";
  for (std::size_t k = 0; k < trails.size(); ++k) {
    nlohmann::json trail = nlohmann::json::array();
    for (const auto& p : trails[k]) trail.push_back({p.x, p.y});
    nlohmann::json r{{"rover", k}, {"trail", std::move(trail)}, {"pose", nullptr}};
    if (!trails[k].empty()) {
      const Pose& p = trails[k].back();
      r["pose"] = poseJson(p.x, p.y, p.headingDeg);
    }
    if (k < beliefs.size()) {
      r["believed_trail"] = beliefs[k];
      std::vector<std::array<float, 2>>().swap(beliefs[k]);
    }
    if (k > 0) rovers += ',';
    rovers += r.dump();
    std::vector<Pose>().swap(trails[k]);
  }
  rovers += ']';
  std::string text = j.dump();
  const std::string placeholder = "\"rovers\":null";
  // The last occurrence: keys are sorted and only "status", "step" and "type" (no such text)
  // follow the top-level "rovers"; a NaN metric named "rovers" would come earlier.
  const auto at = text.rfind(placeholder);
  text.replace(at, placeholder.size(), "\"rovers\":" + rovers);
  snap->json = std::make_shared<const std::string>(std::move(text));
  ++snapshotBuilds_;
  std::lock_guard lock(mutex_);
  snapshot_ = snap;
  return snap;
}

void MissionStream::cutLocked() {
  Cursors c;
  c.cut = head_.cut + 1;
  c.state = stateVersion_;
  c.grid = gridVersionLocked();
  c.route = routeVersion_;
  c.progress = progressVersion_;
  c.status = statusVersion_;
  c.step = step_;
  for (const auto& t : trails_) c.trails.push_back(t.size());
  for (const auto& b : beliefs_) c.beliefs.push_back(b.size());
  for (const auto& p : paths_) c.paths.push_back(p.size());
  // Progress and status are overwritten in place: their frames are taken now, as of this cut.
  if (c.progress != head_.progress) {
    nlohmann::json j = progress_;
    j["type"] = "progress";
    if (!liveMetrics_.is_null()) j["metrics"] = liveMetrics_;
    progressFrame_ = std::make_shared<const std::string>(j.dump());
    ++frameEncodes_;
  }
  if (c.status != head_.status) {
    statusFrame_ = std::make_shared<const std::string>(nlohmann::json{{"type", "status"}, {"status", enumName(status_)}}.dump());
    ++frameEncodes_;
  }
  head_ = std::move(c);
  headAt_ = std::chrono::steady_clock::now();
  batches_.clear();  // the subscribers holding one keep it alive until sent
}

std::shared_ptr<const MissionStream::Batch> MissionStream::batchLocked(const Cursors& from) {
  const Cursors& h = head_;
  auto at = [](const std::vector<std::size_t>& v, std::size_t k) { return k < v.size() ? v[k] : 0; };
  auto batch = std::make_shared<Batch>();
  auto text = [&](const nlohmann::json& j) {
    batch->emplace_back(false, std::make_shared<const std::string>(j.dump()), false);
    ++frameEncodes_;
  };

  // The team route (replaced whole) and the planned paths' new points.
  nlohmann::json overlay{{"type", "overlay"}};
  if (from.route != h.route) overlay["route"] = route_;
  nlohmann::json paths = nlohmann::json::array();
  for (std::size_t k = 0; k < h.paths.size(); ++k) {
    const std::size_t a = std::min(at(from.paths, k), h.paths[k]);
    if (a == h.paths[k]) continue;
    nlohmann::json append(std::vector<std::array<float, 2>>(paths_[k].begin() + static_cast<std::ptrdiff_t>(a),
                                                            paths_[k].begin() + static_cast<std::ptrdiff_t>(h.paths[k])));
    paths.push_back({{"rover", k}, {"append", std::move(append)}});
  }
  if (overlay.contains("route") || !paths.empty()) {
    overlay["paths"] = std::move(paths);
    text(overlay);
  }

  // The grid: a diff, or the full grid (shared) when the diff would be bigger or the log no
  // longer reaches back to `from`.
  if (grid_.cellCount() > 0 && from.grid != h.grid) {
    const bool full = from.grid < logBase_ || h.grid - from.grid > static_cast<std::uint64_t>(grid_.cellCount()) / 2;
    if (full) {
      batch->emplace_back(true, sharedFullGridLocked(), false);
    } else {
      batch->emplace_back(true, std::make_shared<const std::string>(gridDiffFrame(from.grid, h.grid)), false);
      ++frameEncodes_;
    }
  }

  // The rovers' new trail points (and believed points), each rover's pose as of the cut.
  nlohmann::json rovers = nlohmann::json::array();
  for (std::size_t k = 0; k < h.trails.size(); ++k) {
    const std::size_t a = std::min(at(from.trails, k), h.trails[k]);
    const std::size_t hb = at(h.beliefs, k), b = std::min(at(from.beliefs, k), hb);
    if (a == h.trails[k] && b == hb) continue;
    nlohmann::json append = nlohmann::json::array();
    for (std::size_t i = a; i < h.trails[k]; ++i) append.push_back({trails_[k][i].x, trails_[k][i].y});
    nlohmann::json r{{"rover", k}, {"append", std::move(append)}, {"pose", nullptr}};
    if (h.trails[k] > 0) {
      const Pose& p = trails_[k][h.trails[k] - 1];
      r["pose"] = poseJson(p.x, p.y, p.headingDeg);
    }
    if (b < hb)
      r["believed"] = std::vector<std::array<float, 2>>(beliefs_[k].begin() + static_cast<std::ptrdiff_t>(b),
                                                        beliefs_[k].begin() + static_cast<std::ptrdiff_t>(hb));
    rovers.push_back(std::move(r));
  }
  if (!rovers.empty()) text({{"type", "poses"}, {"step", h.step}, {"rovers", std::move(rovers)}});

  if (from.progress != h.progress && progressFrame_) batch->emplace_back(false, progressFrame_, false);
  // After the end the done frame carries the status.
  if (from.status != h.status && statusFrame_ && !finished_) batch->emplace_back(false, statusFrame_, false);
  return batch;
}

void MissionStream::cellsChanged(std::span<const CellUpdate> cells) {
  {
    std::lock_guard lock(mutex_);
    allocateGridLocked();
    ++stateVersion_;
    for (const CellUpdate& c : cells) {
      if (c.index < 0 || c.index >= grid_.cellCount()) continue;
      state_[c.index] = c.state;
      if (c.visits > 0 || c.state != 3) visits_[c.index] = std::max(visits_[c.index], c.visits);
      changeLog_.push_back(c.index);
    }
    // Bound the log: clients behind a compaction get a full grid instead of a diff.
    if (changeLog_.size() > 2 * static_cast<std::size_t>(std::max(1, grid_.cellCount())) + 1024) {
      logBase_ += changeLog_.size();
      changeLog_.clear();
    }
  }
  wakeAll(false);
}

void MissionStream::roverPoses(std::int64_t step, std::span<const RoverPose> poses) {
  {
    std::lock_guard lock(mutex_);
    step_ = step;
    ++stateVersion_;
    for (const RoverPose& p : poses) {
      if (p.rover < 0) continue;
      if (static_cast<std::size_t>(p.rover) >= trails_.size()) trails_.resize(p.rover + 1);
      auto& t = trails_[p.rover];
      Pose q{static_cast<float>(p.x), static_cast<float>(p.y),
             static_cast<float>(p.heading * 180.0 / std::numbers::pi)};
      if (t.empty() || t.back().x != q.x || t.back().y != q.y) t.push_back(q);
      else t.back().headingDeg = q.headingDeg;
      if (p.hasBelief) {
        if (beliefs_.size() < trails_.size()) beliefs_.resize(trails_.size());
        auto& b = beliefs_[p.rover];
        const std::array<float, 2> xy{static_cast<float>(p.believedX), static_cast<float>(p.believedY)};
        if (b.empty() || b.back() != xy) b.push_back(xy);
      }
    }
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
    progress_ = {{"step", p.step}, {"fraction", p.fraction}, {"coverage", p.coverage}, {"moves", p.moves}};
    if (p.phase == Progress::Phase::Planning) {
      progress_["phase"] = "planning";
      progress_["legs_done"] = p.legsDone;
      progress_["legs_total"] = p.legsTotal;
    } else if (p.phase == Progress::Phase::Replay) {
      progress_["phase"] = "replay";
      progress_["mission_time_s"] = p.missionTime;
      progress_["mission_end_s"] = p.missionEnd;
    }
    if (p.phase != Progress::Phase::None) {
      progress_["replans"] = p.replans;
      progress_["waits"] = p.waits;
    }
    ++progressVersion_;
    ++stateVersion_;
  }
  wakeAll(false);
}

void MissionStream::overlay(std::string_view kind, int rover, std::span<const Point2> points) {
  {
    std::lock_guard lock(mutex_);
    ++stateVersion_;
    if (kind == "route") {
      route_.clear();
      for (const auto& p : points) route_.push_back({static_cast<float>(p.x), static_cast<float>(p.y)});
      ++routeVersion_;
    } else if (kind == "path" && rover >= 0 && rover < 4096) {
      if (static_cast<std::size_t>(rover) >= paths_.size()) paths_.resize(rover + 1);
      for (const auto& p : points) paths_[rover].push_back({static_cast<float>(p.x), static_cast<float>(p.y)});
    }
  }
  wakeAll(false);
}

void MissionStream::metrics(std::span<const Metric> metrics) {
  {
    std::lock_guard lock(mutex_);
    liveMetrics_ = nlohmann::json::object();
    for (const auto& m : metrics) liveMetrics_[m.key] = m.value;
    ++progressVersion_;
    ++stateVersion_;
  }
  wakeAll(false);
}

nlohmann::json MissionStream::overlaysJson() const {
  std::lock_guard lock(mutex_);
  return {{"route", route_}, {"paths", paths_}};
}

void MissionStream::restoreOverlays(const nlohmann::json& o) {
  std::lock_guard lock(mutex_);
  if (!o.is_object()) return;
  ++stateVersion_;
  try {
    route_ = o.value("route", std::vector<std::array<float, 2>>{});
    paths_ = o.value("paths", std::vector<std::vector<std::array<float, 2>>>{});
    ++routeVersion_;
  } catch (const nlohmann::json::exception&) {
    route_.clear();
    paths_.clear();
  }
}

nlohmann::json MissionStream::beliefsJson() const {
  std::lock_guard lock(mutex_);
  return beliefs_;
}

void MissionStream::restoreBeliefs(const nlohmann::json& b) {
  std::lock_guard lock(mutex_);
  if (!b.is_array() || b.size() > 4096) return;
  ++stateVersion_;
  try {
    beliefs_ = b.get<std::vector<std::vector<std::array<float, 2>>>>();
  } catch (const nlohmann::json::exception&) {
    beliefs_.clear();
  }
}

void MissionStream::setStatus(RunStatus status) {
  {
    std::lock_guard lock(mutex_);
    status_ = status;
    ++statusVersion_;
    ++stateVersion_;
  }
  wakeAll(true);
}

void MissionStream::finish(RunStatus status, const std::string& message,
                           const nlohmann::json& metrics) {
  {
    std::lock_guard lock(mutex_);
    status_ = status;
    message_ = message;
    metrics_ = metrics;
    finished_ = true;
    ++statusVersion_;
    ++stateVersion_;
  }
  wakeAll(true);
}

bool MissionStream::finished() const {
  std::lock_guard lock(mutex_);
  return finished_;
}

nlohmann::json MissionStream::summary() const {
  std::lock_guard lock(mutex_);
  return {{"status", enumName(status_)}, {"step", step_}, {"progress", progress_}, {"metrics", metrics_},
          {"message", message_}, {"subscribers", subscribers_.size()}};
}

std::string MissionStream::fullGridFrame() const {
  std::lock_guard lock(mutex_);
  return fullGridFrameLocked();
}

std::string MissionStream::fullGridFrameLocked() const {
  std::string out;
  const auto n = static_cast<std::uint32_t>(grid_.cellCount());
  out.reserve(16 + 5 * n);
  putU32(out, kFullGrid);
  putU32(out, grid_.rows);
  putU32(out, grid_.cols);
  putU32(out, n);
  if (state_.empty()) {
    out.append(5ull * n, '\0');  // nothing reported yet (queued): every cell unknown, unvisited
    return out;
  }
  out.append(reinterpret_cast<const char*>(state_.data()), n);
  for (std::uint32_t v : visits_) putU32(out, v);
  return out;
}

std::string MissionStream::gridDiffFrame(std::uint64_t since, std::uint64_t until) const {
  // Latest state of every cell changed in [since, until), each cell once.
  std::vector<std::int32_t> cells;
  diffSeen_.resize(static_cast<std::size_t>(grid_.cellCount()), 0);
  for (std::size_t i = since - logBase_; i < until - logBase_; ++i) {
    const std::int32_t c = changeLog_[i];
    if (!diffSeen_[c]) diffSeen_[c] = 1, cells.push_back(c);
  }
  for (std::int32_t c : cells) diffSeen_[c] = 0;
  std::string out;
  out.reserve(16 + 12 * cells.size());
  putU32(out, kCellUpdates);
  putU32(out, grid_.rows);
  putU32(out, grid_.cols);
  putU32(out, static_cast<std::uint32_t>(cells.size()));
  for (std::int32_t c : cells) {
    putU32(out, static_cast<std::uint32_t>(c));
    out.push_back(static_cast<char>(state_[c]));
    out.append(3, '\0');
    putU32(out, visits_[c]);
  }
  return out;
}

nlohmann::json MissionStream::trailsJson() const {
  std::lock_guard lock(mutex_);
  nlohmann::json all = nlohmann::json::array();
  for (const auto& t : trails_) {
    nlohmann::json pts = nlohmann::json::array();
    for (const auto& p : t) pts.push_back({p.x, p.y, p.headingDeg});
    all.push_back(pts);
  }
  return all;
}

std::shared_ptr<MissionStream> MissionStream::fromStored(const std::string& missionId,
                                                         const std::string& gridFrame,
                                                         const nlohmann::json& trails,
                                                         RunStatus status,
                                                         const std::string& message,
                                                         const nlohmann::json& metrics) {
  GridGeometry g{};
  if (gridFrame.size() >= 16 && getU32(gridFrame, 0) == kFullGrid) {
    g.rows = static_cast<int>(getU32(gridFrame, 4));
    g.cols = static_cast<int>(getU32(gridFrame, 8));
    if (gridFrame.size() != 16 + 5ull * g.rows * g.cols) g = GridGeometry{};
  }
  auto s = std::make_shared<MissionStream>(missionId, g, static_cast<int>(trails.size()));
  s->allocateGridLocked();  // not shared yet: no lock needed
  for (int i = 0; i < g.cellCount(); ++i) {
    s->state_[i] = static_cast<std::uint8_t>(gridFrame[16 + i]);
    s->visits_[i] = getU32(gridFrame, 16 + g.cellCount() + 4ull * i);
  }
  for (std::size_t k = 0; k < trails.size(); ++k)
    for (const auto& p : trails[k])
      s->trails_[k].push_back({p.at(0).get<float>(), p.at(1).get<float>(), p.size() > 2 ? p.at(2).get<float>() : 0.0f});
  s->finish(status, message, metrics);
  return s;
}

std::shared_ptr<http::WsSource> MissionStream::subscribe(std::shared_ptr<http::WsConnection> connection) {
  {
    std::lock_guard lock(mutex_);
    std::erase_if(subscribers_, [](const auto& w) { return w.expired(); });
    subscribers_.push_back(connection);
  }
  return std::make_shared<Subscription>(shared_from_this());
}

std::size_t MissionStream::subscriberCount() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& w : subscribers_) n += !w.expired();
  return n;
}

void MissionStream::wakeAll(bool force) {
  std::vector<std::shared_ptr<http::WsConnection>> live;
  {
    std::lock_guard lock(mutex_);
    // The planner may emit thousands of events a second: they are published as a cut at most
    // every kCutEvery, and only a cut wakes the subscribers (who then find a batch to send).
    // Lifecycle changes cut and wake at once.
    if (subscribers_.empty() || !dirtyLocked()) return;
    if (!force && std::chrono::steady_clock::now() - headAt_ < kCutEvery) return;
    cutLocked();
    for (const auto& w : subscribers_)
      if (auto c = w.lock()) live.push_back(std::move(c));
  }
  for (auto& c : live) c->wake();
}

}  // namespace rover::missions
