#include "server/missions/mission_channels.hpp"

#include "server/json/plan_json.hpp"

#include <algorithm>
#include <numbers>

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

std::size_t textFrame(Batch& out, const nlohmann::json& j) {
  out.emplace_back(false, std::make_shared<const std::string>(j.dump()), false);
  return 1;
}

}  // namespace

nlohmann::json poseJson(float x, float y, float headingDeg) {
  return {{"x", x}, {"y", y}, {"heading_deg", headingDeg}};
}

// --- overlay ---

void OverlayChannel::add(std::string_view kind, int rover, std::span<const Point2> points) {
  if (kind == "route") {
    route_.clear();
    for (const auto& p : points) route_.push_back({static_cast<float>(p.x), static_cast<float>(p.y)});
    ++routeVersion_;
  } else if (kind == "path" && rover >= 0 && rover < 4096) {
    if (static_cast<std::size_t>(rover) >= paths_.size()) paths_.resize(rover + 1);
    for (const auto& p : points) paths_[rover].push_back({static_cast<float>(p.x), static_cast<float>(p.y)});
  }
}

nlohmann::json OverlayChannel::json() const { return {{"route", route_}, {"paths", paths_}}; }

void OverlayChannel::restore(const nlohmann::json& o) {
  try {
    route_ = o.value("route", std::vector<XY>{});
    paths_ = o.value("paths", std::vector<std::vector<XY>>{});
    ++routeVersion_;
  } catch (const nlohmann::json::exception&) {
    route_.clear();
    paths_.clear();
  }
}

Position OverlayChannel::position() const {
  Position p{routeVersion_};
  for (const auto& path : paths_) p.push_back(path.size());
  return p;
}

std::size_t OverlayChannel::frames(const Position& from, const Position& to, Batch& out) {
  // The team route (replaced whole) and the planned paths' new points.
  nlohmann::json overlay{{"type", "overlay"}};
  if (streams::lengthAt(from, 0) != streams::lengthAt(to, 0)) overlay["route"] = route_;
  nlohmann::json paths = nlohmann::json::array();
  for (std::size_t k = 0; k + 1 < to.size(); ++k) {
    const std::size_t end = to[k + 1], a = std::min<std::size_t>(streams::lengthAt(from, k + 1), end);
    if (a == end) continue;
    nlohmann::json append(std::vector<XY>(paths_[k].begin() + static_cast<std::ptrdiff_t>(a),
                                          paths_[k].begin() + static_cast<std::ptrdiff_t>(end)));
    paths.push_back({{"rover", k}, {"append", std::move(append)}});
  }
  if (!overlay.contains("route") && paths.empty()) return 0;
  overlay["paths"] = std::move(paths);
  return textFrame(out, overlay);
}

// --- grid ---

void GridChannel::allocate() {
  if (!state_.empty() || grid_.cellCount() <= 0) return;
  state_.assign(grid_.cellCount(), 0);
  visits_.assign(grid_.cellCount(), 0);
}

void GridChannel::apply(std::span<const CellUpdate> cells) {
  allocate();
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

GridGeometry GridChannel::geometryOf(const std::string& frame) {
  GridGeometry g{};
  if (frame.size() >= 16 && getU32(frame, 0) == kFullGrid) {
    g.rows = static_cast<int>(getU32(frame, 4));
    g.cols = static_cast<int>(getU32(frame, 8));
    if (frame.size() != 16 + 5ull * g.rows * g.cols) g = GridGeometry{};
  }
  return g;
}

void GridChannel::restore(const std::string& frame) {
  allocate();
  for (int i = 0; i < grid_.cellCount(); ++i) {
    state_[i] = static_cast<std::uint8_t>(frame[16 + i]);
    visits_[i] = getU32(frame, 16 + grid_.cellCount() + 4ull * i);
  }
}

std::shared_ptr<const std::string> GridChannel::sharedFullFrame() {
  const std::uint64_t v = version();
  if (!full_ || fullVersion_ != v) {
    full_ = std::make_shared<const std::string>(fullFrame());
    fullVersion_ = v;
  }
  return full_;
}

std::string GridChannel::fullFrame() const {
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

std::string GridChannel::diffFrame(std::uint64_t since, std::uint64_t until) const {
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

std::size_t GridChannel::frames(const Position& fromPos, const Position& toPos, Batch& out) {
  const std::uint64_t from = streams::lengthAt(fromPos, 0), to = streams::lengthAt(toPos, 0);
  if (!present() || from == to) return 0;
  // A diff, or the full grid (shared) when the diff would be bigger or the log no longer
  // reaches back to `from`.
  if (from < logBase_ || to - from > static_cast<std::uint64_t>(grid_.cellCount()) / 2) {
    out.emplace_back(true, sharedFullFrame(), false);
    return 0;
  }
  out.emplace_back(true, std::make_shared<const std::string>(diffFrame(from, to)), false);
  return 1;
}

// --- poses ---

void PosesChannel::apply(std::int64_t step, std::span<const RoverPose> poses) {
  step_ = step;
  for (const RoverPose& p : poses) {
    if (p.rover < 0) continue;
    if (static_cast<std::size_t>(p.rover) >= trails_.size()) trails_.resize(p.rover + 1);
    auto& t = trails_[p.rover];
    Pose q{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.heading * 180.0 / std::numbers::pi)};
    if (t.empty() || t.back().x != q.x || t.back().y != q.y) t.push_back(q);
    else t.back().headingDeg = q.headingDeg;
    if (p.hasBelief) {
      if (beliefs_.size() < trails_.size()) beliefs_.resize(trails_.size());
      auto& b = beliefs_[p.rover];
      const XY xy{static_cast<float>(p.believedX), static_cast<float>(p.believedY)};
      if (b.empty() || b.back() != xy) b.push_back(xy);
    }
  }
}

nlohmann::json PosesChannel::trailsJson() const {
  nlohmann::json all = nlohmann::json::array();
  for (const auto& t : trails_) {
    nlohmann::json pts = nlohmann::json::array();
    for (const auto& p : t) pts.push_back({p.x, p.y, p.headingDeg});
    all.push_back(pts);
  }
  return all;
}

void PosesChannel::restoreBeliefs(const nlohmann::json& b) {
  try {
    beliefs_ = b.get<std::vector<std::vector<XY>>>();
  } catch (const nlohmann::json::exception&) {
    beliefs_.clear();
  }
}

Position PosesChannel::position() const {
  Position p{static_cast<std::uint64_t>(step_)};
  for (std::size_t k = 0; k < trails_.size(); ++k) {
    p.push_back(trails_[k].size());
    p.push_back(k < beliefs_.size() ? beliefs_[k].size() : 0);
  }
  return p;
}

std::size_t PosesChannel::frames(const Position& from, const Position& to, Batch& out) {
  // The rovers' new trail points (and believed points), each rover's pose as of `to`.
  nlohmann::json rovers = nlohmann::json::array();
  for (std::size_t k = 0; 2 * k + 2 < to.size(); ++k) {
    const std::size_t ht = to[2 * k + 1], hb = to[2 * k + 2];
    const std::size_t a = std::min<std::size_t>(streams::lengthAt(from, 2 * k + 1), ht);
    const std::size_t b = std::min<std::size_t>(streams::lengthAt(from, 2 * k + 2), hb);
    if (a == ht && b == hb) continue;
    nlohmann::json append = nlohmann::json::array();
    for (std::size_t i = a; i < ht; ++i) append.push_back({trails_[k][i].x, trails_[k][i].y});
    nlohmann::json r{{"rover", k}, {"append", std::move(append)}, {"pose", nullptr}};
    if (ht > 0) {
      const Pose& p = trails_[k][ht - 1];
      r["pose"] = poseJson(p.x, p.y, p.headingDeg);
    }
    if (b < hb)
      r["believed"] = std::vector<XY>(beliefs_[k].begin() + static_cast<std::ptrdiff_t>(b),
                                      beliefs_[k].begin() + static_cast<std::ptrdiff_t>(hb));
    rovers.push_back(std::move(r));
  }
  if (rovers.empty()) return 0;
  return textFrame(out, {{"type", "poses"}, {"step", static_cast<std::int64_t>(to[0])}, {"rovers", std::move(rovers)}});
}

// --- incidents ---

void IncidentChannel::add(std::span<const Incident> found, bool complete) {
  if (complete) {
    items_ = nlohmann::json::array();
    ++replaced_;
    complete_ = true;
  }
  for (const Incident& i : found) items_.push_back(json::toJson(i));
}

std::size_t IncidentChannel::frames(const Position& from, const Position& to, Batch& out) {
  // From the reader's position to the list as it is now (it may have grown, or been replaced,
  // since the cut `to`): the frame says where its incidents start, so a reader that is sent some
  // of them again keeps its list right.
  (void)to;
  const bool sameList = streams::lengthAt(from, 0) == replaced_;
  const std::size_t start = sameList ? std::min<std::size_t>(streams::lengthAt(from, 1), items_.size()) : 0;
  if (sameList && start == items_.size()) return 0;
  nlohmann::json list(items_.begin() + static_cast<std::ptrdiff_t>(start), items_.end());
  return textFrame(out, {{"type", "incidents"}, {"from", start}, {"complete", complete_}, {"incidents", std::move(list)}});
}

// --- values: progress and status ---

std::size_t ValueChannel::cut(const Position& from, const Position& to) {
  if (streams::lengthAt(from, 0) == streams::lengthAt(to, 0)) return 0;
  frame_ = std::make_shared<const std::string>(frameJson().dump());
  return 1;
}

std::size_t ValueChannel::frames(const Position& from, const Position& to, Batch& out) {
  if (streams::lengthAt(from, 0) != streams::lengthAt(to, 0) && frame_ && !silent())
    out.emplace_back(false, frame_, false);
  return 0;
}

void ProgressChannel::set(const Progress& p) {
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
  changed();
}

void ProgressChannel::setMetrics(std::span<const Metric> metrics) {
  liveMetrics_ = nlohmann::json::object();
  for (const auto& m : metrics) liveMetrics_[m.key] = m.value;
  changed();
}

nlohmann::json ProgressChannel::frameJson() const {
  nlohmann::json j = progress_;
  j["type"] = "progress";
  if (!liveMetrics_.is_null()) j["metrics"] = liveMetrics_;
  return j;
}

void StatusChannel::set(RunStatus status) {
  status_ = status;
  changed();
}

void StatusChannel::finish(RunStatus status, const std::string& message, const nlohmann::json& metrics) {
  status_ = status;
  message_ = message;
  metrics_ = metrics;
  finished_ = true;
  changed();
}

}  // namespace rover::missions
