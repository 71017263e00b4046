#include "server/studies/study_manager.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/common/error.hpp"
#include "server/errors/domain_error.hpp"
#include "server/store/database.hpp"
#include "server/store/disk_budget.hpp"
#include "server/studies/studies.hpp"
#include "server/studies/study_summary.hpp"

extern char** environ;

namespace rover::studies {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

constexpr auto kSummaryEvery = std::chrono::seconds(3);  // partial summary on the stream
constexpr auto kCommitEvery = std::chrono::milliseconds(500);
constexpr std::size_t kCommitRuns = 500;

json readJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  return json::parse(in);
}

// The spec document of a POST body: a study spec as it is, or {"preset", "runs", "master_seed"}.
// The server reads no file a request names: DEM worlds are refused, and the swinton preset runs on
// its synthetic Mars world only.
json documentOf(const json& body) {
  if (!body.is_object()) throw DomainError(Refusal::BadJson, "the request body must be a JSON object", "body");
  if (body.contains("preset")) {
    for (const auto& item : body.items())
      if (item.key() != "preset" && item.key() != "runs" && item.key() != "master_seed" && item.key() != "name")
        throw DomainError(Refusal::UnknownField, "with a preset only runs, master_seed and name may be given",
                          item.key().substr(0, 64));
    if (!body["preset"].is_string()) throw DomainError(Refusal::InvalidField, "preset must be a string", "preset");
    PresetOptions o;
    o.hirisePath = "";
    if (body.contains("runs")) {
      const json& r = body["runs"];
      if (!r.is_number_integer() || r.get<std::int64_t>() < 1 || r.get<std::int64_t>() > kMaxRuns)
        throw DomainError(Refusal::InvalidField, "runs must be an integer in [1, " + std::to_string(kMaxRuns) + "]", "runs");
      o.runs = r.get<int>();
    }
    if (body.contains("master_seed")) {
      if (!body["master_seed"].is_number_unsigned())
        throw DomainError(Refusal::InvalidField, "master_seed must be a non-negative integer", "master_seed");
      o.masterSeed = body["master_seed"].get<std::uint64_t>();
    }
    json spec = presetSpecJson(body["preset"].get<std::string>(), o);
    if (body.contains("name")) spec["name"] = body["name"];  // checked with the spec, by the name rule
    return spec;
  }
  if (const auto w = body.find("worlds"); w != body.end() && w->is_array())
    for (std::size_t i = 0; i < w->size(); ++i)
      if ((*w)[i].is_object() && (*w)[i].contains("dem"))
        throw DomainError(Refusal::InvalidField, "the server reads no file a request names: use grid or terrain worlds",
                          "worlds[" + std::to_string(i) + "].dem");
  return body;
}

}  // namespace

std::vector<std::string> splitCommandLine(const std::string& line) {
  std::vector<std::string> out;
  std::string word;
  bool inWord = false;
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
      else if (c == '\\' && quote == '"' && i + 1 < line.size()) word += line[++i];
      else word += c;
    } else if (c == '\'' || c == '"') {
      quote = c;
      inWord = true;
    } else if (c == '\\' && i + 1 < line.size()) {
      word += line[++i];
      inWord = true;
    } else if (c == ' ' || c == '\t' || c == '\n') {
      if (inWord) out.push_back(std::move(word));
      word.clear();
      inWord = false;
    } else {
      word += c;
      inWord = true;
    }
  }
  if (quote) throw std::invalid_argument("an unclosed quote");
  if (inWord) out.push_back(std::move(word));
  return out;
}

bool isEnded(const std::string& status) {
  return status == "succeeded" || status == "cancelled" || status == "failed";
}

json toJson(const StudyState& s) {
  return {{"id", s.id},
          {"name", s.name},
          {"status", s.status},
          {"message", s.message},
          {"created_at", s.createdAt},
          {"started_at", s.startedAt},
          {"finished_at", s.finishedAt},
          {"runs_done", s.done},
          {"runs_total", s.total},
          {"eta_s", s.etaSeconds < 0 ? json(nullptr) : json(std::round(s.etaSeconds))},
          {"runs_per_s", s.runsPerSecond},
          {"links",
           {{"self", "/api/studies/" + s.id},
            {"stream", "/api/studies/" + s.id + "/stream"},
            {"runs_csv", "/api/studies/" + s.id + "/runs.csv"},
            {"sqlite", "/api/studies/" + s.id + "/study.sqlite"}}}};
}

// --- the stream ---

class StudyStream::Subscription : public http::WsSource {
 public:
  explicit Subscription(std::shared_ptr<StudyStream> s) : stream_(std::move(s)) {}
  std::optional<http::WsFrame> next() override {
    StudyStream& s = *stream_;
    std::lock_guard lock(s.mutex_);
    if (doneSent_) return std::nullopt;
    const auto progressJson = [&s] {
      return json{{"type", "progress"}, {"status", s.state_.status},     {"message", s.state_.message},
                  {"runs_done", s.state_.done}, {"runs_total", s.state_.total},
                  {"eta_s", s.state_.etaSeconds < 0 ? json(nullptr) : json(std::round(s.state_.etaSeconds))},
                  {"runs_per_s", s.state_.runsPerSecond}};
    };
    if (!snapshotSent_) {
      snapshotSent_ = true;
      seen_ = s.version_;
      summarySeen_ = s.summaryVersion_;
      return http::WsFrame{false, s.encodedLocked(s.snapshot_, true, [&s] {
                             return json{{"type", "snapshot"}, {"study", toJson(s.state_)}, {"summary", s.summary_}};
                           })};
    }
    if (isEnded(s.state_.status)) {
      doneSent_ = true;
      return http::WsFrame{false,
                           s.encodedLocked(s.done_, true, [&s] {
                             return json{{"type", "done"}, {"status", s.state_.status}, {"message", s.state_.message},
                                         {"runs_done", s.state_.done}, {"runs_total", s.state_.total},
                                         {"summary", s.summary_}};
                           }),
                           true};
    }
    if (seen_ == s.version_ && summarySeen_ == s.summaryVersion_) return std::nullopt;
    seen_ = s.version_;
    if (summarySeen_ != s.summaryVersion_) {
      summarySeen_ = s.summaryVersion_;
      return http::WsFrame{false, s.encodedLocked(s.progressWithSummary_, true, [&] {
                             json j = progressJson();
                             j["summary"] = s.summary_;
                             return j;
                           })};
    }
    return http::WsFrame{false, s.encodedLocked(s.progress_, false, progressJson)};
  }
  std::chrono::milliseconds minInterval() const override { return std::chrono::milliseconds(250); }

 private:
  std::shared_ptr<StudyStream> stream_;
  bool snapshotSent_ = false, doneSent_ = false;
  std::uint64_t seen_ = 0, summarySeen_ = 0;
};

std::shared_ptr<const std::string> StudyStream::encodedLocked(Encoded& slot, bool withSummary,
                                                              const std::function<json()>& make) const {
  const std::uint64_t summaryVersion = withSummary ? summaryVersion_ : 0;
  if (!slot.bytes || slot.version != version_ || slot.summaryVersion != summaryVersion) {
    slot.bytes = std::make_shared<const std::string>(make().dump());
    slot.version = version_;
    slot.summaryVersion = summaryVersion;
    ++encodes_;
  }
  return slot.bytes;
}

std::uint64_t StudyStream::frameEncodes() const {
  std::lock_guard lock(mutex_);
  return encodes_;
}

void StudyStream::update(const StudyState& state) {
  {
    std::lock_guard lock(mutex_);
    state_ = state;
    ++version_;
  }
  wakeAll();
}

void StudyStream::setSummary(json summary) {
  {
    std::lock_guard lock(mutex_);
    summary_ = std::move(summary);
    ++summaryVersion_;
  }
  wakeAll();
}

void StudyStream::wakeAll() {
  std::vector<std::shared_ptr<http::WsConnection>> live;
  {
    std::lock_guard lock(mutex_);
    std::erase_if(subscribers_, [](const auto& w) { return w.expired(); });
    for (const auto& w : subscribers_)
      if (auto c = w.lock()) live.push_back(std::move(c));
  }
  for (const auto& c : live) c->wake();
}

std::shared_ptr<http::WsSource> StudyStream::subscribe(std::shared_ptr<http::WsConnection> connection) {
  {
    std::lock_guard lock(mutex_);
    subscribers_.push_back(connection);
  }
  return std::make_shared<Subscription>(shared_from_this());
}

// --- the manager ---

StudyManager::StudyManager(store::DataDir& dir, std::function<bool()> missionsBusy, std::vector<std::string> launcher,
                           std::string selfExe)
    : dir_(dir), missionsBusy_(std::move(missionsBusy)), launcher_(std::move(launcher)), selfExe_(std::move(selfExe)) {
  // The launcher runs this binary by its real path (a child of mpirun reading /proc/self/exe
  // would find mpirun); on a cluster that path must be the same on every host (a shared install).
  if (selfExe_ == "/proc/self/exe") {
    std::error_code ec;
    const fs::path real = fs::read_symlink(selfExe_, ec);
    if (!ec) selfExe_ = real.string();
  }
  fs::create_directories(fs::path(dir_.root()) / "studies");
  loadStored();
  worker_ = std::thread([this] { work(); });
}

StudyManager::~StudyManager() { stop(); }

std::string StudyManager::folder(const std::string& id) const {
  return (fs::path(dir_.root()) / "studies" / id).string();
}

void StudyManager::saveState(const StudyState& s) const {
  json j = toJson(s);
  j.erase("links");
  try {
    store::DataDir::writeFileAtomic((fs::path(folder(s.id)) / "state.json").string(), j.dump(1));
  } catch (const std::exception& e) {
    // A full disk: the state stays in memory; the next change writes it again.
    std::cerr << "roverplan: study " << s.id << ": cannot store its state: " << e.what() << "\n";
  }
}

void StudyManager::loadStored() {
  std::vector<StudyState> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir_.root()) / "studies", ec)) {
    if (!e.is_directory()) continue;
    try {
      const json j = readJsonFile((e.path() / "state.json").string());
      StudyState s;
      s.id = j.at("id").get<std::string>();
      if (s.id != e.path().filename().string()) continue;
      s.name = j.value("name", "");
      s.status = j.value("status", "queued");
      s.message = j.value("message", "");
      s.createdAt = j.value("created_at", "");
      s.startedAt = j.value("started_at", "");
      s.finishedAt = j.value("finished_at", "");
      s.done = j.value("runs_done", std::size_t{0});
      s.total = j.value("runs_total", std::size_t{0});
      found.push_back(std::move(s));
    } catch (const std::exception&) {
      // A folder without a readable state (a crash between mkdir and the first write): dropped.
      store::DataDir::removeTree(e.path().string());
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.createdAt < b.createdAt; });
  for (auto& s : found) {
    if (!isEnded(s.status)) {
      // Unfinished at the last stop: queued again; the engine runs only the missing runs.
      s.status = "queued";
      s.message = "resumed after a server restart";
      s.etaSeconds = -1;
      queue_.push_back(s.id);
    }
    Entry e;
    e.state = s;
    e.stream = std::make_shared<StudyStream>();
    e.cancel = std::make_shared<CancelToken>();
    e.stream->update(s);
    studies_.emplace(s.id, std::move(e));
  }
}

StudyState StudyManager::submit(const json& body) {
  dir_.budget().requireRoom(store::DiskUse::Study, "");  // OverBudget when the disk budget is full
  const json doc = documentOf(body);
  const StudySpec spec = parseStudySpec(doc);  // rover::Error naming the field
  if (spec.runCount() > kMaxServerRuns)
    throw DomainError(Refusal::TooManyRuns,
                      "the study has " + std::to_string(spec.runCount()) + " runs; the server runs at most " +
                          std::to_string(kMaxServerRuns) + " per study (use roverplan study run on a cluster)",
                      "runs");
  if (launcher_.empty() && spec.missionThreads > 1)
    throw DomainError(Refusal::InvalidField, "a study on the server plans each run on one thread", "mission_threads");
  StudyState s;
  s.id = store::DataDir::newId();
  s.name = spec.name;
  s.total = spec.runCount();
  s.createdAt = store::nowIso();
  {
    std::lock_guard lock(mutex_);
    std::size_t active = 0;
    for (const auto& [id, e] : studies_) active += !isEnded(e.state.status);
    if (active >= kMaxActive)
      throw DomainError(Refusal::TooManyStudies,
                        std::to_string(kMaxActive) + " studies are queued or running: wait for one to end or cancel one")
          .retryAfter(std::chrono::seconds(60));
    if (studies_.size() >= kMaxStored)
      throw DomainError(Refusal::TooManyStudies,
                        "the server keeps at most " + std::to_string(kMaxStored) + " studies: delete ended ones");
  }
  const std::string dirPath = folder(s.id);
  fs::create_directories(dirPath);
  try {
    store::DataDir::writeFileAtomic((fs::path(dirPath) / "spec.json").string(), spec.json.dump(1));
    json j = toJson(s);
    j.erase("links");
    store::DataDir::writeFileAtomic((fs::path(dirPath) / "state.json").string(), j.dump(1));
  } catch (...) {
    store::DataDir::removeTree(dirPath);
    throw;
  }
  {
    std::lock_guard lock(mutex_);
    Entry e;
    e.state = s;
    e.stream = std::make_shared<StudyStream>();
    e.cancel = std::make_shared<CancelToken>();
    e.stream->update(s);
    studies_.emplace(s.id, std::move(e));
    queue_.push_back(s.id);
  }
  cv_.notify_all();
  return s;
}

std::vector<StudyState> StudyManager::list() const {
  std::lock_guard lock(mutex_);
  std::vector<StudyState> out;
  for (const auto& [id, e] : studies_) out.push_back(e.state);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.createdAt != b.createdAt ? a.createdAt > b.createdAt : a.id > b.id;
  });
  return out;
}

std::optional<StudyState> StudyManager::get(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = studies_.find(id);
  if (it == studies_.end()) return std::nullopt;
  return it->second.state;
}

json StudyManager::specJson(const std::string& id) const { return readJsonFile((fs::path(folder(id)) / "spec.json").string()); }

std::string StudyManager::databasePath(const std::string& id) const {
  const fs::path p = fs::path(folder(id)) / "study.sqlite";
  std::error_code ec;
  return fs::is_regular_file(p, ec) ? p.string() : std::string();
}

json StudyManager::storedSummary(const std::string& id) const {
  std::error_code ec;
  const fs::path saved = fs::path(folder(id)) / "summary.json";
  if (fs::is_regular_file(saved, ec)) {
    try {
      return readJsonFile(saved.string());
    } catch (const std::exception&) {
      // Unreadable (cut short by a full disk): the database still has every run.
    }
  }
  const std::string path = databasePath(id);
  if (path.empty()) return nullptr;
  StudyDb db = StudyDb::open(path);  // a second connection: WAL readers do not block the writer
  if (!db.hasSpec()) return nullptr;
  return toJson(db.summary());
}

json StudyManager::summary(const std::string& id) {
  std::shared_ptr<std::mutex> once;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return nullptr;
    if (it->second.summary) return *it->second.summary;
    once = it->second.summaryOnce;
  }
  std::lock_guard reading(*once);  // a second reader waits here, then finds it
  std::uint64_t version = 0;
  bool ended = false;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return nullptr;
    if (it->second.summary) return *it->second.summary;
    version = it->second.summaryVersion;
    ended = isEnded(it->second.state.status);
  }
  const fs::path saved = fs::path(folder(id)) / "summary.json";
  std::error_code ec;
  const bool wasSaved = fs::exists(saved, ec);
  json s = storedSummary(id);
  if (ended && !wasSaved && !s.is_null()) {
    try {  // an ended study of an older version: read once, kept for the next start
      store::DataDir::writeFileAtomic(saved.string(), s.dump());
    } catch (const std::exception&) {
    }
  }
  std::lock_guard lock(mutex_);
  auto it = studies_.find(id);
  // Kept unless the study published a newer one meanwhile.
  if (it != studies_.end() && it->second.summaryVersion == version)
    it->second.summary = std::make_shared<const json>(s);
  return s;
}

void StudyManager::publishSummary(const std::string& id, const json& summary) {
  auto shared = std::make_shared<const json>(summary);
  std::lock_guard lock(mutex_);
  auto it = studies_.find(id);
  if (it == studies_.end()) return;
  it->second.summary = std::move(shared);
  ++it->second.summaryVersion;
}

std::string StudyManager::runsCsvFile(const std::string& id) const {
  // Streamed from the database into a file of the study's folder (temp + rename, so a download
  // in progress keeps its own copy): memory stays small however many runs the study has.
  const fs::path out = fs::path(folder(id)) / "runs.csv";
  const fs::path temp = fs::path(folder(id)) / ("runs.csv." + store::DataDir::newId());
  {
    std::ofstream f(temp, std::ios::binary);
    if (!f) throw std::runtime_error("cannot write " + temp.string());
    const std::string path = databasePath(id);
    if (!path.empty()) {
      StudyDb db = StudyDb::open(path);
      if (db.hasSpec()) db.runsCsv(f);
    }
    f.flush();
    if (!f) {
      std::error_code ec;
      fs::remove(temp, ec);
      throw store::StorageFull("the study's runs.csv");
    }
  }
  fs::rename(temp, out);
  return out.string();
}

std::shared_ptr<StudyStream> StudyManager::stream(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = studies_.find(id);
  return it == studies_.end() ? nullptr : it->second.stream;
}

StudyManager::Removal StudyManager::remove(const std::string& id) {
  std::unique_lock lock(mutex_);
  auto it = studies_.find(id);
  if (it == studies_.end()) return Removal::NotFound;
  Entry& e = it->second;
  if (!isEnded(e.state.status)) {
    e.state.cancelRequested = true;
    e.cancel->cancel();
    if (auto q = std::find(queue_.begin(), queue_.end(), id); q != queue_.end()) {
      // Never started in this session: it ends here.
      queue_.erase(q);
      lock.unlock();
      finish(id, "cancelled", "cancelled before it started");
    }
    return Removal::Cancelling;
  }
  studies_.erase(it);
  lock.unlock();
  dir_.remove(folder(id));
  return Removal::Deleted;
}

void StudyManager::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && !worker_.joinable()) return;
    stopping_ = true;
    for (auto& [id, e] : studies_) e.cancel->cancel();
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void StudyManager::finish(const std::string& id, const std::string& status, const std::string& message) {
  // An ended study's summary never changes: kept beside it (before it is seen ended), so a restart
  // need not read its runs.
  json final = nullptr;
  try {
    final = summary(id);
    if (!final.is_null()) store::DataDir::writeFileAtomic((fs::path(folder(id)) / "summary.json").string(), final.dump());
  } catch (const std::exception&) {
    // A full disk: the summary stays in memory; after a restart it is read from the database.
  }
  StudyState s;
  std::shared_ptr<StudyStream> stream;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return;
    it->second.state.status = status;
    it->second.state.message = message;
    it->second.state.finishedAt = store::nowIso();
    it->second.state.etaSeconds = status == "succeeded" ? 0 : -1;
    s = it->second.state;
    stream = it->second.stream;
  }
  stream->setSummary(final);
  saveState(s);
  dir_.budget().record(folder(id), store::DiskUse::Study, "", store::bytesUnder(folder(id)));
  stream->update(s);
}

void StudyManager::chargeDisk(const std::string& id) const {
  // A stat of the few files in the folder: cheap enough at every commit.
  dir_.budget().charge(folder(id), store::DiskUse::Study, "", store::bytesUnder(folder(id)));
}

void StudyManager::report(const std::string& id, std::size_t done, std::size_t total, std::size_t doneAtStart,
                          Clock::time_point start, const std::function<json()>& summaryOf,
                          Clock::time_point& lastSummary) {
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  const double rate = elapsed > 0 ? static_cast<double>(done - doneAtStart) / elapsed : 0;
  StudyState s;
  std::shared_ptr<StudyStream> stream;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return;
    auto& st = it->second.state;
    st.done = done;
    st.total = total;
    st.runsPerSecond = rate;
    st.etaSeconds = rate > 0 ? static_cast<double>(total - done) / rate : -1;
    s = st;
    stream = it->second.stream;
  }
  stream->update(s);
  if (Clock::now() - lastSummary >= kSummaryEvery) {
    lastSummary = Clock::now();
    try {
      stream->setSummary(summaryOf());
    } catch (const std::exception&) {
      // A summary is a courtesy while it runs; the next one comes a few seconds later.
    }
  }
}

void StudyManager::work() {
  for (;;) {
    std::string id;
    std::shared_ptr<CancelToken> cancel;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
      Entry& e = studies_.at(id);
      cancel = e.cancel;
      e.state.status = "running";
      if (e.state.startedAt.empty()) e.state.startedAt = store::nowIso();
      saveState(e.state);
      e.stream->update(e.state);
    }
    std::string status = "succeeded", message;
    try {
      if (launcher_.empty()) runInProcess(id, *cancel);
      else runLaunched(id, *cancel);
    } catch (const Error& e) {
      status = "failed";
      message = e.what();
    } catch (const store::StorageFull& e) {  // the disk, or the disk budget, is full
      status = "failed";
      message = std::string("insufficient storage: ") + e.what() + " (the runs stored are kept)";
    } catch (const std::exception& e) {
      status = "failed";
      message = "the study stopped on an internal error (details are in the server log)";
      std::cerr << "roverplan: study " << id << ": " << e.what() << "\n";
    }
    bool userCancel = false;
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;  // left unfinished: the next start resumes it
      auto it = studies_.find(id);
      if (it == studies_.end()) continue;
      userCancel = it->second.state.cancelRequested;
      if (status == "succeeded" && it->second.state.done < it->second.state.total && !userCancel) {
        status = "failed";
        if (message.empty()) message = "the study ended with runs missing";
      }
    }
    if (userCancel && status != "failed") {
      status = "cancelled";
      message = "cancelled; the runs done are kept";
    }
    finish(id, status, message);
  }
}

void StudyManager::runInProcess(const std::string& id, const CancelToken& cancel) {
  const StudySpec spec = parseStudySpec(specJson(id));
  const StudyRunner runner(spec);
  StudyDb db = StudyDb::open((fs::path(folder(id)) / "study.sqlite").string());
  db.attach(spec);
  const std::vector<std::size_t> todo = runner.pending(db);
  const std::size_t total = spec.runCount(), doneAtStart = total - todo.size();
  std::size_t done = doneAtStart;
  const auto start = Clock::now();
  auto lastSummary = Clock::now() - kSummaryEvery;
  auto lastCommit = Clock::now();
  // The summary follows the commits (what is stored, nothing more): built from the runs stored
  // at the start, then each batch merged in.
  SummaryAccumulator acc(spec);
  db.accumulate(acc);
  json latest = toJson(acc.summary());
  publishSummary(id, latest);
  const auto summaryOf = [&latest] { return latest; };
  report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
  std::vector<RunRow> batch;
  const auto commit = [&] {
    db.insert(batch);
    acc.add(batch);
    latest = toJson(acc.summary());
    publishSummary(id, latest);
    done += batch.size();
    batch.clear();
    lastCommit = Clock::now();
    report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
    chargeDisk(id);  // OverBudget ends the study (failed) with the runs committed so far
  };
  for (const std::size_t index : todo) {
    // Below the missions: wait (committing what is done) while they want the machine.
    while (!cancel.cancelled() && missionsBusy_ && missionsBusy_()) {
      if (!batch.empty()) commit();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (cancel.cancelled()) break;
    std::optional<RunRow> row = runner.runOne(index, &cancel);
    if (!row) break;
    batch.push_back(std::move(*row));
    if (batch.size() >= kCommitRuns || Clock::now() - lastCommit >= kCommitEvery) commit();
  }
  commit();
}

void StudyManager::runLaunched(const std::string& id, const CancelToken& cancel) {
  const std::string dirPath = folder(id);
  const std::string specPath = (fs::path(dirPath) / "spec.json").string();
  const std::string dbPath = (fs::path(dirPath) / "study.sqlite").string();
  const std::string logPath = (fs::path(dirPath) / "launcher.log").string();
  std::vector<std::string> argv = launcher_;
  for (const char* a : {"study", "run", "--spec"}) argv.push_back(a);
  argv.insert(argv.begin() + static_cast<std::ptrdiff_t>(launcher_.size()), selfExe_);
  argv.push_back(specPath);
  argv.push_back("--out");
  argv.push_back(dbPath);
  argv.push_back("--quiet");
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, logPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // The server blocks SIGINT/SIGTERM for its sigwait; the child gets them back.
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, cargv[0], &actions, &attr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (rc != 0)
    throw Error(ErrorCode::InvalidInput, "launcher",
                "the study launcher '" + launcher_[0] + "' could not be started: " + std::strerror(rc));

  const StudySpec spec = parseStudySpec(specJson(id));
  const std::size_t total = spec.runCount();
  std::optional<StudyDb> db;
  std::size_t doneAtStart = 0, done = 0;
  bool first = true;
  const auto start = Clock::now();
  auto lastSummary = Clock::now() - kSummaryEvery;
  // The child writes the database: its summary is read from it every few seconds (report) and
  // published for the GETs.
  const auto summaryOf = [&] {
    json s = db && db->hasSpec() ? toJson(db->summary()) : json(nullptr);
    publishSummary(id, s);
    return s;
  };
  int status = 0;
  bool signalled = false;
  std::optional<store::OverBudget> overBudget;  // the child was stopped for it
  for (;;) {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (cancel.cancelled() && !signalled) {
      kill(pid, SIGTERM);  // mpirun forwards it to its ranks
      signalled = true;
    }
    if (!overBudget) {
      try {
        chargeDisk(id);
      } catch (const store::OverBudget& e) {
        overBudget.emplace(e);
        kill(pid, SIGTERM);
        signalled = true;
      }
    }
    try {
      if (!db && !databasePath(id).empty()) db.emplace(StudyDb::open(dbPath));
      if (db && db->hasSpec()) {
        const std::size_t n = db->runCount();
        if (first) doneAtStart = n, first = false;
        done = n;
      }
    } catch (const std::exception&) {
      db.reset();  // the child is still creating it
    }
    report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (!db && !databasePath(id).empty()) db.emplace(StudyDb::open(dbPath));
  done = db && db->hasSpec() ? db->runCount() : 0;
  lastSummary = Clock::now() - kSummaryEvery;
  report(id, done, total, first ? done : doneAtStart, start, summaryOf, lastSummary);
  if (overBudget) throw *overBudget;
  if (signalled) return;
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (code != 0)
    throw Error(ErrorCode::InvalidInput, "launcher",
                "the study command exited with status " + std::to_string(code) +
                    " (its output is in the study's launcher.log on the server)");
}

}  // namespace rover::studies
