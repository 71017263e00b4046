// roverplan serve (issue: server): the planning server on Boost.Beast.
#include <signal.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/common/parallel.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/routes.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/token_file.hpp"
#include "server/http/http_server.hpp"
#include "server/jail/import_jail.hpp"
#include "server/missions/mission_manager.hpp"
#include "server/store/disk_budget.hpp"

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

// The bearer token, from at most one of --token, --token-file and ROVERPLAN_TOKEN. The variable is
// removed once read, so no child (a study launcher, an import worker) inherits it. A token file
// may hold several tokens, `name:token` lines naming their operator (token_file.hpp): they go in
// `named`, and the first is returned.
std::string serverToken(const ArgParser& a, std::vector<std::pair<std::string, std::string>>& named) {
  const char* env = std::getenv("ROVERPLAN_TOKEN");
  const std::string fromEnv = env ? env : "";
  ::unsetenv("ROVERPLAN_TOKEN");
  const int sources = (a.has("token") ? 1 : 0) + (a.has("token-file") ? 1 : 0) + (fromEnv.empty() ? 0 : 1);
  if (sources > 1) throw UsageError("give the token once: --token, --token-file or ROVERPLAN_TOKEN");
  std::string token;
  if (a.has("token-file")) {
    const std::string path = a.str("token-file", "");
    std::ifstream in(path);
    if (!in) throw UsageError("--token-file: cannot read " + path);
    try {
      named = parseTokenFile(in);
    } catch (const std::invalid_argument& e) {
      throw UsageError("--token-file " + path + ": " + e.what());
    }
    return named.front().second;
  } else {
    token = a.has("token") ? a.str("token", "") : fromEnv;
  }
  if (a.has("token") && token.empty()) throw UsageError("--token: the token is empty");
  for (unsigned char c : token)
    if (c < 0x21 || c > 0x7e) throw UsageError("the token must be printable ASCII without spaces");
  return token;
}

std::vector<std::string> commaList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The data directory holds uploads, plans and the database: nobody else's to read. Everything the
// server creates is 0600/0700 (umask), and a directory made by an older version is tightened.
void keepDataPrivate(const store::DataDir& dir) {
  std::error_code ec;
  fs::permissions(dir.root(), fs::perms::owner_all, fs::perm_options::replace, ec);
  for (const char* suffix : {"", "-wal", "-shm"})
    if (fs::exists(dir.databasePath() + suffix, ec))
      fs::permissions(dir.databasePath() + suffix, fs::perms::owner_read | fs::perms::owner_write,
                      fs::perm_options::replace, ec);
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
  a.option("token", "T", "",
           "Require 'Authorization: Bearer T' on every /api route except health. Visible to every "
           "local user in `ps`: prefer ROVERPLAN_TOKEN or --token-file.");
  a.option("token-file", "F", "", "Read the tokens from F (keep it 0600): one a line, `token` or `name:token` (that operator's name "
           "in events and history).");
  a.option("workers", "N", "cores", "Missions run in parallel.");
  a.option("queue", "N", "64", "Missions that may wait; more are refused with 429.");
  a.option("mission-memory-mb", "M", "half the RAM",
           "Memory the running + queued missions may take together (their estimates): one larger "
           "is refused with 413, more with 429.");
  // A 300 M-cell map (the cell budget) is 1.2 GB as an uncompressed float32 GeoTIFF.
  a.option("max-upload-mb", "M", "2048", "Largest accepted upload.");
  a.option("disk-budget-mb", "M", "90% of the data directory's file system",
           "Disk the data directory may fill: maps, PDMs, layer files, mission results and studies "
           "together. Beyond it a write is refused with 507 disk_budget_full, a mission or study fails.");
  a.option("map-disk-budget-mb", "M", "2048",
           "Disk one map's PDMs, layer files and mission results may take together; beyond it 507 "
           "disk_budget_full, and 413 too_large for one object larger than the whole budget.");
  a.option("layer-cache-mb", "M", "1024",
           "Rendered layer files kept (PNG/GeoTIFF/f32 of every map); the least recently used are "
           "deleted beyond it.");
  a.option("work-threads", "N", "2",
           "Threads for slow requests (DEM imports, layer renders, PDMs, mission validation), "
           "apart from the 2 HTTP threads.");
  a.option("work-queue", "N", "32", "Slow requests that may wait for a work thread; more get 503.");
  a.option("min-upload-kibps", "K", "16",
           "Slowest accepted request body: K KiB/s averaged over any 10 s (slower: 408).");
  a.option("cors", "ORIGIN", "",
           "Allow cross-origin requests, state changes and live streams from pages of ORIGIN (e.g. "
           "http://localhost:5173). Without it only the server's own page may change state: a "
           "POST/PUT/PATCH/DELETE or WebSocket with a foreign Origin gets 403.");
  a.option("public-name", "NAMES", "",
           "Comma-separated host names (or addresses) clients use to reach the server, answered "
           "besides localhost, 127.0.0.0/8, ::1 and --host; any other Host gets 421 (a DNS-rebinding "
           "guard). '*' answers every name.");
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
  config.token = serverToken(a, config.namedTokens);
  config.corsOrigin = a.str("cors", "");
  config.publicNames = commaList(a.str("public-name", ""));
  config.maxUploadBytes = static_cast<std::uint64_t>(a.integer("max-upload-mb", 2048, 1, 1 << 20)) << 20;
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

  ::umask(077);
  store::DataDir dir(a.str("data", "roverplan-data"));
  keepDataPrivate(dir);
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
  store::DiskBudgetLimits budget;
  budget.globalBytes = a.has("disk-budget-mb")
                           ? static_cast<std::uint64_t>(a.integer("disk-budget-mb", 0, 1, 1ll << 40)) << 20
                           : store::defaultDiskBudget(dir.root());
  budget.perMapBytes = static_cast<std::uint64_t>(a.integer("map-disk-budget-mb", 2048, 1, 1ll << 40)) << 20;
  dir.budget().setLimits(budget);
  api::MapCatalog maps(db, dir, api::MapCatalog::kDefaultMaxCells,
                       static_cast<std::uint64_t>(a.integer("layer-cache-mb", 1024, 1, 1ll << 40)) << 20);
  const int orphans = maps.sweepOrphans();
  store::recountDiskUse(dir, db);  // the layer files were counted by the catalog
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
  // Maps whose COG was not written before the last stop; after the routes, which set the
  // catalog's callback its jobs call.
  const int raw = maps.resumeCompressions();
  // Probed before the first request can arrive (it starts a few test jails), so the lines below
  // follow the URL at once.
  const jail::Isolation isolation = jail::isolation();
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
  out << "imports: client files are parsed in " << jail::isolationInWords(isolation) << std::endl;
  if (a.has("token"))
    out << "warning: --token is visible to every local user in `ps`; prefer ROVERPLAN_TOKEN or --token-file"
        << std::endl;
  if (config.webRoot.empty())
    out << "warning: no web page found (pass --web DIR); serving the API only" << std::endl;
  if (!fullDisk.empty()) out << "warning: " << fullDisk << std::endl;
  if (orphans > 0) out << "removed " << orphans << " half-stored map/PDM folder(s) left by a crash" << std::endl;
  if (raw > 0) out << raw << " map(s) still stored raw: compressing their elevation again" << std::endl;
  if (interrupted > 0) out << interrupted << " mission(s) were running at the last stop: marked interrupted" << std::endl;

  int sig = 0;
  sigwait(&stopSignals, &sig);
  out << "stopping (" << (sig == SIGINT ? "SIGINT" : "SIGTERM") << ")..." << std::endl;
  server.stop();
  maps.compressor().stop();  // its callback uses the API's context; a raw map resumes at the next start
  studyManager.stop();  // an unfinished study resumes at the next start
  manager.stop();
  out << "stopped" << std::endl;
  return 0;
}

}  // namespace rover::cli
