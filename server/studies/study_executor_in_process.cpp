#include <optional>
#include <thread>

#include "server/studies/studies.hpp"
#include "server/studies/study_executor.hpp"
#include "server/studies/study_summary.hpp"

namespace rover::studies {

using nlohmann::json;
using Clock = StudyClock;

namespace {
constexpr auto kCommitEvery = std::chrono::milliseconds(500);
constexpr std::size_t kCommitRuns = 500;
}  // namespace

void InProcessExecutor::run(const std::string& id, const CancelToken& cancel, StudyReporter& reporter) {
  const StudySpec spec = parseStudySpec(store_.specJson(id));
  const StudyRunner runner(spec);
  StudyDb db = StudyDb::open(store_.file(id, "study.sqlite"));
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
  reporter.publishSummary(id, latest);
  const auto summaryOf = [&latest] { return latest; };
  reporter.report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
  std::vector<RunRow> batch;
  const auto commit = [&] {
    db.insert(batch);
    acc.add(batch);
    latest = toJson(acc.summary());
    reporter.publishSummary(id, latest);
    done += batch.size();
    batch.clear();
    lastCommit = Clock::now();
    reporter.report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
    store_.chargeDisk(id);  // OverBudget ends the study (failed) with the runs committed so far
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

}  // namespace rover::studies
