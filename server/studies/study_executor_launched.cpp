#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <optional>
#include <thread>

#include "core/common/error.hpp"
#include "server/store/disk_budget.hpp"
#include "server/studies/studies.hpp"
#include "server/studies/study_executor.hpp"
#include "server/studies/study_summary.hpp"

extern char** environ;

namespace rover::studies {

using nlohmann::json;
using Clock = StudyClock;

LaunchedExecutor::LaunchedExecutor(const StudyStore& store, std::vector<std::string> launcher, std::string selfExe)
    : store_(store), launcher_(std::move(launcher)), selfExe_(std::move(selfExe)) {
  // The launcher runs this binary by its real path (a child of mpirun reading /proc/self/exe
  // would find mpirun); on a cluster that path must be the same on every host (a shared install).
  if (selfExe_ == "/proc/self/exe") {
    std::error_code ec;
    const std::filesystem::path real = std::filesystem::read_symlink(selfExe_, ec);
    if (!ec) selfExe_ = real.string();
  }
}

void LaunchedExecutor::run(const std::string& id, const CancelToken& cancel, StudyReporter& reporter) {
  const std::string specPath = store_.file(id, "spec.json");
  const std::string dbPath = store_.file(id, "study.sqlite");
  const std::string logPath = store_.file(id, "launcher.log");
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

  const StudySpec spec = parseStudySpec(store_.specJson(id));
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
    reporter.publishSummary(id, s);
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
        store_.chargeDisk(id);
      } catch (const store::OverBudget& e) {
        overBudget.emplace(e);
        kill(pid, SIGTERM);
        signalled = true;
      }
    }
    try {
      if (!db && !store_.databasePath(id).empty()) db.emplace(StudyDb::open(dbPath));
      if (db && db->hasSpec()) {
        const std::size_t n = db->runCount();
        if (first) doneAtStart = n, first = false;
        done = n;
      }
    } catch (const std::exception&) {
      db.reset();  // the child is still creating it
    }
    reporter.report(id, done, total, doneAtStart, start, summaryOf, lastSummary);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (!db && !store_.databasePath(id).empty()) db.emplace(StudyDb::open(dbPath));
  done = db && db->hasSpec() ? db->runCount() : 0;
  lastSummary = Clock::now() - kSummaryEvery;
  reporter.report(id, done, total, first ? done : doneAtStart, start, summaryOf, lastSummary);
  if (overBudget) throw *overBudget;
  if (signalled) return;
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (code != 0)
    throw Error(ErrorCode::InvalidInput, "launcher",
                "the study command exited with status " + std::to_string(code) +
                    " (its output is in the study's launcher.log on the server)");
}

}  // namespace rover::studies
