// roverplan serve (issue: server): the planning server on Boost.Beast.
#include <signal.h>

#include <filesystem>
#include <iostream>

#include "core/common/parallel.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/routes.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/http/http_server.hpp"
#include "server/missions/mission_manager.hpp"

namespace rover::cli {

namespace {

namespace fs = std::filesystem;

bool holdsPage(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "index.html", ec);
}

// The web root when --web is not given: an installed binary's PREFIX/share/roverplan/web (`cmake
// --install`, the container image), else the source tree's web/ this binary was built from.
std::string defaultWebRoot() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "roverplan" / "web";
    if (holdsPage(installed)) return installed.string();
  }
  return holdsPage(ROVER_WEB_DIR) ? std::string(ROVER_WEB_DIR) : std::string();
}

}  // namespace

int serveCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser a("serve", "The planning server: REST API, live WebSocket streams, the web page.");
  a.option("host", "ADDR", "127.0.0.1", "Address to bind (loopback by default; 0.0.0.0 for all).");
  a.option("port", "N", "8080", "TCP port (0 = any free port).");
  a.option("data", "DIR", "roverplan-data", "Data directory (SQLite database, maps, results).");
  a.option("web", "DIR", "installed",
           "Static web root served at /. Default: PREFIX/share/roverplan/web next to an installed "
           "binary, else the source tree's web/.");
  a.option("token", "T", "", "Require 'Authorization: Bearer T' on every /api route except health.");
  a.option("workers", "N", "cores", "Missions run in parallel.");
  a.option("queue", "N", "64", "Missions that may wait; more are refused with 429.");
  a.option("mission-memory-mb", "M", "half the RAM",
           "Memory the running + queued missions may take together (their estimates): one larger "
           "is refused with 413, more with 429.");
  a.option("max-upload-mb", "M", "512", "Largest accepted upload.");
  a.option("work-threads", "N", "2",
           "Threads for slow requests (DEM imports, layer renders, PDMs, mission validation), "
           "apart from the 2 HTTP threads.");
  a.option("work-queue", "N", "32", "Slow requests that may wait for a work thread; more get 503.");
  a.option("min-upload-kibps", "K", "16",
           "Slowest accepted request body: K KiB/s averaged over any 10 s (slower: 408).");
  a.option("cors", "ORIGIN", "", "Allow cross-origin requests from ORIGIN (off by default).");
  a.option("study-launcher", "CMD", "",
           "Run each study as CMD + `roverplan study run --spec F --out DB` (e.g. \"mpirun -np 16 "
           "--hostfile H\"; split into words like a shell, run without one); default: in the server.");
  a.option("max-stream-subscribers", "N", "64",
           "WebSocket subscribers one mission or study stream may have; more get 503 with Retry-After.");
  a.option("max-subscribers", "N", "1024", "WebSocket subscribers of all streams together; more get 503.");
  a.flag("quiet", "Do not log one line per request.");
  if (!a.parse(argv)) {
    out << a.help();
    return 0;
  }
  http::ServerConfig config;
  config.host = a.str("host", config.host);
  config.port = static_cast<unsigned short>(a.integer("port", 8080, 0, 65535));
  if (a.has("web")) {
    config.webRoot = a.str("web", "");
    if (!holdsPage(config.webRoot))
      throw UsageError("--web: " + config.webRoot + " is not a folder holding index.html");
  } else {
    config.webRoot = defaultWebRoot();  // "" = API only, said at start
  }
  config.token = a.str("token", "");
  config.corsOrigin = a.str("cors", "");
  config.maxUploadBytes = static_cast<std::uint64_t>(a.integer("max-upload-mb", 512, 1, 1 << 20)) << 20;
  config.logRequests = !a.isSet("quiet");
  config.workThreads = static_cast<unsigned>(a.integer("work-threads", 2, 1, 256));
  config.workQueue = static_cast<std::size_t>(a.integer("work-queue", 32, 0, 100000));
  config.minBodyRate = static_cast<std::uint64_t>(a.integer("min-upload-kibps", 16, 0, 1 << 20)) << 10;
  config.maxStreamSubscribers = static_cast<std::size_t>(a.integer("max-stream-subscribers", 64, 1, 1000000));
  config.maxSubscribers = static_cast<std::size_t>(a.integer("max-subscribers", 1024, 1, 1000000));
  const unsigned workers = static_cast<unsigned>(a.integer("workers", hardwareThreads(), 1, 256));
  const std::size_t queue = static_cast<std::size_t>(a.integer("queue", 64, 0, 100000));
  const std::uint64_t defaultBudgetMb = missions::defaultMissionMemoryBudget() >> 20;
  const std::uint64_t missionMemory =
      static_cast<std::uint64_t>(a.integer("mission-memory-mb", static_cast<long long>(defaultBudgetMb), 1, 1ll << 30)) << 20;

  // Block the stop signals before any thread starts, so only sigwait below receives them.
  sigset_t stopSignals;
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

  store::DataDir dir(a.str("data", "roverplan-data"));
  dir.cleanTmp();  // uploads in flight when the server last died: never visible
  config.uploadDir = dir.tmpDir();
  store::Database db(dir.databasePath());
  // A full disk does not stop the start: reads work, writes answer 507 until space frees.
  std::string fullDisk;
  int interrupted = 0;
  try {
    interrupted = db.markUnfinishedInterrupted();
  } catch (const store::StorageFull& e) {
    fullDisk = e.what();  // they are marked at the next start with room
  }
  api::MapCatalog maps(db, dir);
  const int orphans = maps.sweepOrphans();
  try {
    maps.ensureDefaultMap();
  } catch (const store::StorageFull& e) {
    fullDisk = e.what();
  }
  if (dir.startedFull() && fullDisk.empty()) fullDisk = "the data directory's disk is full";
  PlannerRegistry planners = makeBuiltinRegistry();
  missions::MissionManager manager(db, dir, planners, workers, queue, missionMemory);
  std::vector<std::string> launcher;
  try {
    launcher = studies::splitCommandLine(a.str("study-launcher", ""));
  } catch (const std::exception& e) {
    throw UsageError(std::string("--study-launcher: ") + e.what());
  }
  // Studies run below the missions: a study takes its next run only when no mission waits and the
  // running missions leave a core free.
  const unsigned cores = hardwareThreads();
  studies::StudyManager studyManager(
      dir, [&manager, cores] { return manager.queued() > 0 || manager.running() >= cores; }, launcher);
  http::Router router;
  api::ApiContext ctx{db, dir, maps, manager, planners};
  ctx.studies = &studyManager;
  api::addApiRoutes(router, ctx);
  http::HttpServer server(config, router);
  try {
    server.start();
  } catch (const std::exception& e) {
    throw UsageError(std::string("cannot start the server: ") + e.what());
  }
  std::string shownHost = config.host == "0.0.0.0" ? "127.0.0.1" : config.host;
  out << "roverplan serving on http://" << shownHost << ":" << server.port() << "/  (data: "
      << std::filesystem::absolute(dir.root()).string() << ", " << workers << " workers, "
      << missions::formatBytes(missionMemory) << " mission memory"
      << (config.token.empty() ? "" : ", token required")
      << (launcher.empty() ? "" : ", studies launched by " + launcher[0]) << ")" << std::endl;
  if (config.webRoot.empty())
    out << "warning: no web page found (pass --web DIR); serving the API only" << std::endl;
  if (!fullDisk.empty()) out << "warning: " << fullDisk << std::endl;
  if (orphans > 0) out << "removed " << orphans << " half-stored map/PDM folder(s) left by a crash" << std::endl;
  if (interrupted > 0) out << interrupted << " mission(s) were running at the last stop: marked interrupted" << std::endl;

  int sig = 0;
  sigwait(&stopSignals, &sig);
  out << "stopping (" << (sig == SIGINT ? "SIGINT" : "SIGTERM") << ")..." << std::endl;
  server.stop();
  studyManager.stop();  // an unfinished study resumes at the next start
  manager.stop();
  out << "stopped" << std::endl;
  return 0;
}

}  // namespace rover::cli
