#include "server/studies/study_manager.hpp"

#include <algorithm>
#include <iostream>

#include "core/common/error.hpp"
#include "server/errors/domain_error.hpp"
#include "server/store/database.hpp"
#include "server/studies/studies.hpp"

namespace rover::studies {

using nlohmann::json;

StudyManager::StudyManager(store::DataDir& dir, std::function<bool()> missionsBusy, std::vector<std::string> launcher,
                           std::string selfExe)
    : store_(dir), scheduler_([this](const std::string& id) { runOne(id); }) {
  if (launcher.empty()) executor_ = std::make_unique<InProcessExecutor>(store_, std::move(missionsBusy));
  else executor_ = std::make_unique<LaunchedExecutor>(store_, std::move(launcher), std::move(selfExe));
  for (StudyState& s : store_.load()) {
    if (!isFinal(s.status)) {
      // Unfinished at the last stop: queued again; the engine runs only the missing runs.
      s.status = RunStatus::Queued;
      s.message = "resumed after a server restart";
      s.etaSeconds = -1;
      scheduler_.push(s.id);
    }
    Entry e;
    e.state = s;
    e.stream = std::make_shared<StudyStream>();
    e.cancel = std::make_shared<CancelToken>();
    e.stream->update(s);
    studies_.emplace(s.id, std::move(e));
  }
  scheduler_.start();
}

StudyManager::~StudyManager() { stop(); }

StudyState StudyManager::submit(const StudySpec& spec) {
  store_.requireRoom();  // OverBudget when the disk budget is full
  if (spec.runCount() > kMaxServerRuns)
    throw DomainError(Refusal::TooManyRuns,
                      "the study has " + std::to_string(spec.runCount()) + " runs; the server runs at most " +
                          std::to_string(kMaxServerRuns) + " per study (use roverplan study run on a cluster)",
                      "runs");
  if (!executor_->multithreadedRuns() && spec.missionThreads > 1)
    throw DomainError(Refusal::InvalidField, "a study on the server plans each run on one thread", "mission_threads");
  StudyState s;
  s.id = store::DataDir::newId();
  s.name = spec.name;
  s.total = spec.runCount();
  s.createdAt = store::nowIso();
  {
    std::lock_guard lock(mutex_);
    std::size_t active = 0;
    for (const auto& [id, e] : studies_) active += !isFinal(e.state.status);
    if (active >= kMaxActive)
      throw DomainError(Refusal::TooManyStudies,
                        std::to_string(kMaxActive) + " studies are queued or running: wait for one to end or cancel one")
          .retryAfter(std::chrono::seconds(60));
    if (studies_.size() >= kMaxStored)
      throw DomainError(Refusal::TooManyStudies,
                        "the server keeps at most " + std::to_string(kMaxStored) + " studies: delete ended ones");
  }
  store_.create(s, spec.json);
  {
    std::lock_guard lock(mutex_);
    Entry e;
    e.state = s;
    e.stream = std::make_shared<StudyStream>();
    e.cancel = std::make_shared<CancelToken>();
    e.stream->update(s);
    studies_.emplace(s.id, std::move(e));
  }
  scheduler_.push(s.id);
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

json StudyManager::specJson(const std::string& id) const { return store_.specJson(id); }

std::string StudyManager::databasePath(const std::string& id) const { return store_.databasePath(id); }

std::string StudyManager::runsCsvFile(const std::string& id) const { return store_.runsCsvFile(id); }
std::string StudyManager::benchmarkDbFile(const std::string& id) const { return store_.benchmarkDbFile(id); }

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
    ended = isFinal(it->second.state.status);
  }
  const bool wasSaved = store_.hasSavedSummary(id);
  json s = store_.storedSummary(id);
  if (ended && !wasSaved && !s.is_null()) {
    try {  // an ended study of an older version: read once, kept for the next start
      store_.saveSummary(id, s);
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

std::shared_ptr<StudyStream> StudyManager::stream(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = studies_.find(id);
  return it == studies_.end() ? nullptr : it->second.stream;
}

store::Cas StudyManager::rename(const std::string& id, const std::string& name, long long expected, StudyState& out) {
  std::shared_ptr<StudyStream> stream;
  {
    // Under the lock with the file write, as every other state.json write: a status change cannot
    // write an older name over this one.
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return store::Cas::Missing;
    out = it->second.state;
    if (out.version != expected) return store::Cas::Stale;
    out.name = name;
    ++out.version;
    store_.writeState(out);
    it->second.state = out;
    stream = it->second.stream;
  }
  stream->update(out);
  return store::Cas::Done;
}

StudyManager::Removal StudyManager::remove(const std::string& id) {
  std::unique_lock lock(mutex_);
  auto it = studies_.find(id);
  if (it == studies_.end()) return Removal::NotFound;
  Entry& e = it->second;
  if (!isFinal(e.state.status)) {
    e.state.cancelRequested = true;
    e.cancel->cancel();
    if (scheduler_.withdraw(id)) {
      // Never started in this session: it ends here.
      lock.unlock();
      finish(id, RunStatus::Cancelled, "cancelled before it started");
    }
    return Removal::Cancelling;
  }
  studies_.erase(it);
  lock.unlock();
  store_.remove(id);
  return Removal::Deleted;
}

void StudyManager::stop() {
  scheduler_.beginStop();  // first: the study cancelled below is left unfinished, not ended
  {
    std::lock_guard lock(mutex_);
    for (auto& [id, e] : studies_) e.cancel->cancel();
  }
  scheduler_.stop();
}

void StudyManager::finish(const std::string& id, RunStatus status, const std::string& message) {
  // An ended study's summary never changes: kept beside it (before it is seen ended), so a restart
  // need not read its runs.
  json final = nullptr;
  try {
    final = summary(id);
    if (!final.is_null()) store_.saveSummary(id, final);
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
    it->second.state.etaSeconds = status == RunStatus::Succeeded ? 0 : -1;
    s = it->second.state;
    stream = it->second.stream;
    store_.saveState(s);  // under the lock: a rename cannot land between the copy and the write
  }
  stream->setSummary(final);
  store_.recordDisk(id);
  stream->update(s);
}

void StudyManager::report(const std::string& id, std::size_t done, std::size_t total, std::size_t doneAtStart,
                          StudyClock::time_point start, const std::function<json()>& summaryOf,
                          StudyClock::time_point& lastSummary) {
  const double elapsed = std::chrono::duration<double>(StudyClock::now() - start).count();
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
  if (StudyClock::now() - lastSummary >= kSummaryEvery) {
    lastSummary = StudyClock::now();
    try {
      stream->setSummary(summaryOf());
    } catch (const std::exception&) {
      // A summary is a courtesy while it runs; the next one comes a few seconds later.
    }
  }
}

void StudyManager::runOne(const std::string& id) {
  std::shared_ptr<CancelToken> cancel;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return;
    Entry& e = it->second;
    cancel = e.cancel;
    e.state.status = RunStatus::Running;
    if (e.state.startedAt.empty()) e.state.startedAt = store::nowIso();
    store_.saveState(e.state);
    e.stream->update(e.state);
  }
  RunStatus status = RunStatus::Succeeded;
  std::string message;
  try {
    executor_->run(id, *cancel, *this);
  } catch (const Error& e) {
    status = RunStatus::Failed;
    message = e.what();
  } catch (const store::StorageFull& e) {  // the disk, or the disk budget, is full
    status = RunStatus::Failed;
    message = std::string("insufficient storage: ") + e.what() + " (the runs stored are kept)";
  } catch (const std::exception& e) {
    status = RunStatus::Failed;
    message = "the study stopped on an internal error (details are in the server log)";
    std::cerr << "roverplan: study " << id << ": " << e.what() << "\n";
  }
  if (scheduler_.stopping()) return;  // left unfinished: the next start resumes it
  bool userCancel = false;
  {
    std::lock_guard lock(mutex_);
    auto it = studies_.find(id);
    if (it == studies_.end()) return;
    userCancel = it->second.state.cancelRequested;
    if (status == RunStatus::Succeeded && it->second.state.done < it->second.state.total && !userCancel) {
      status = RunStatus::Failed;
      if (message.empty()) message = "the study ended with runs missing";
    }
  }
  if (userCancel && status != RunStatus::Failed) {
    status = RunStatus::Cancelled;
    message = "cancelled; the runs done are kept";
  }
  finish(id, status, message);
}

}  // namespace rover::studies
