// `roverplan sweep`: a preset study (server/studies) run on this machine's threads, its summary
// printed and written as summary.json / summary.csv; the same engine as `roverplan study run`.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "core/common/parallel.hpp"
#include "core/planning/rover_limits.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/study_output.hpp"
#include "server/studies/studies.hpp"

namespace rover::cli {

namespace {

std::vector<std::string> list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string c; std::getline(ss, c, ',');) out.push_back(c);
  return out;
}

}  // namespace

int sweepCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("sweep",
                 "Many seeded runs of a preset study on all cores, summarised as mean, std, p5, p50, p95 per "
                 "configuration (SPEC §4); `roverplan study run --preset` runs the same into a database.");
  args.option("preset", "NAME", "", "laine-fig6 | laine-fig8 | frontier | swinton (required).");
  args.option("runs", "N", "3000 (frontier: 1000, swinton: 20)", "Seeded runs per configuration (swinton: random PDMs per site).");
  args.option("hirise", "FILE", "../shared/dems/mars_gale_hirise_1m/missionDEM.tif",
              "swinton: the HiRISE DEM cropped to its central 150 × 150 m at 0.25 m ('none' = synthetic site only).");
  args.option("configs", "LIST", "all", "swinton: any of lhc_gw_conv,lhc,lawnmower,orienteering,hybrid (all: the paper's four, orienteering by name).");
  args.option("coordination", "LIST", "timed", "swinton: timed and/or paper; paper rows are named CONFIG+paper.");
  args.option("rovers", "N", "5", "swinton: rovers per mission.");
  args.option("targets", "N", "64", "swinton: route targets per mission.");
  args.option("seed", "S", "1", "Master seed; run k of every configuration uses the seed derived from (S, k).");
  args.option("threads", "N", "all cores", "Worker threads.");
  args.option("mission-threads", "N", "1", "swinton: threads each mission plans on (cpu_s then counts the mission's calling thread only).");
  args.option("out", "DIR", "", "Write summary.json, summary.csv and the study database study.sqlite into DIR.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (!args.has("preset")) throw UsageError("missing --preset (laine-fig6, laine-fig8, frontier, swinton)");
  const std::string preset = args.str("preset", "");
  studies::PresetOptions o;
  o.runs = static_cast<int>(args.integer("runs", 0, 1, studies::kMaxRuns));
  o.masterSeed = static_cast<std::uint64_t>(args.integer("seed", 1, 0, INT64_MAX));
  o.missionThreads = static_cast<unsigned>(args.integer("mission-threads", 1, 1, 1024));
  o.rovers = static_cast<int>(args.integer("rovers", 5, 1, planning::kMaxRovers));
  o.targets = static_cast<int>(args.integer("targets", 64, 1, 10000));
  o.hirisePath = args.str("hirise", o.hirisePath);
  if (o.hirisePath == "none") o.hirisePath.clear();
  if (args.has("configs")) o.configs = list(args.str("configs", ""));
  if (args.has("coordination")) o.coordination = list(args.str("coordination", ""));
  const unsigned threads = static_cast<unsigned>(args.integer("threads", hardwareThreads(), 1, 1024));
  const studies::StudySpec spec = orUsage([&] {
    try {
      return studies::parseStudySpec(studies::presetSpecJson(preset, o));
    } catch (const Error& e) {
      if (e.field() == "configs" || e.field() == "coordination") throw UsageError("invalid value for --" + e.field() + ": " + e.what());
      throw;
    }
  });

  // A sweep starts afresh: its database is DIR/study.sqlite, or none kept.
  std::string dbPath = ":memory:";
  if (args.has("out")) {
    const std::filesystem::path dir = args.str("out", "");
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    dbPath = (dir / "study.sqlite").string();
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(dbPath + suffix, ec);
  }
  studies::StudyDb db = studies::StudyDb::open(dbPath);
  const studies::StudyRunner runner(spec);
  out << "sweep " << preset << ": " << spec.configurations.size() << " configurations x " << spec.runs
      << " runs = " << spec.runCount() << " runs, " << threads << " threads\n" << std::flush;
  studies::RunOptions ro;
  ro.threads = threads;
  // Runs that take seconds each (team missions): show progress.
  const bool slow = makeBuiltinRegistry().get(spec.planner).specs().secondsPerRun;
  const studies::RunReport r = runner.run(db, ro, [&](std::size_t done, std::size_t total) {
    if (slow) out << "  [" << done << "/" << total << "]\n" << std::flush;
  });
  // Timing rows only where they are a finding (team missions' seconds), so a coverage sweep's
  // summary files do not depend on the thread count.
  const studies::StudySummary s = db.summary(slow);
  double moves = 0;
  for (const auto& row : s.rows)
    if (row.metric == "moves") moves += row.summary.mean * static_cast<double>(row.summary.count);
  out << "\n" << r.ran << " runs";
  if (moves > 0) out << ", " << std::fixed << std::setprecision(0) << moves << " moves";
  out << ", " << std::fixed << std::setprecision(2) << r.wallSeconds << " s wall\n\n";
  printSummaryTable(out, s);
  if (args.has("out")) {
    writeSummaryFiles(args.str("out", ""), s,
                      {{"preset", preset}, {"runs_per_config", spec.runs}, {"master_seed", spec.masterSeed},
                       {"threads", threads}, {"wall_s", r.wallSeconds}, {"total_runs", spec.runCount()}, {"total_moves", moves}});
    out << "\nwrote " << args.str("out", "") << "/summary.json, summary.csv and study.sqlite\n";
  }
  return 0;
}

}  // namespace rover::cli
