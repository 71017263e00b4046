#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/common/parallel.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/sweep.hpp"
#include "server/cli/team_sweep.hpp"

namespace rover::cli {

namespace {

void printTable(std::ostream& out, const SweepOutcome& o) {
  out << std::left << std::setw(24) << "config" << std::setw(26) << "metric" << std::right
      << std::setw(6) << "n" << std::setw(12) << "mean" << std::setw(12) << "std" << std::setw(12)
      << "p5" << std::setw(12) << "p50" << std::setw(12) << "p95"
      << "\n";
  out << std::fixed << std::setprecision(4);
  std::string last;
  for (const auto& r : o.rows) {
    if (!last.empty() && r.config != last) out << "\n";
    last = r.config;
    out << std::left << std::setw(24) << r.config << std::setw(26) << r.metric << std::right
        << std::setw(6) << r.summary.count << std::setw(12) << r.summary.mean << std::setw(12)
        << r.summary.stddev << std::setw(12) << r.summary.p5 << std::setw(12) << r.summary.p50
        << std::setw(12) << r.summary.p95 << "\n";
  }
}

nlohmann::json num(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

void writeFiles(const std::filesystem::path& dir, const std::string& preset, int runs,
                std::uint64_t seed, unsigned threads, const SweepOutcome& o) {
  std::filesystem::create_directories(dir);
  nlohmann::json rows = nlohmann::json::array();
  std::ofstream csv(dir / "summary.csv");
  csv << "config,metric,runs,n,mean,std,p5,p50,p95,min,max\n";
  for (const auto& r : o.rows) {
    const Summary& s = r.summary;
    rows.push_back({{"config", r.config},
                    {"metric", r.metric},
                    {"runs", r.runs},
                    {"n", s.count},
                    {"mean", num(s.mean)},
                    {"std", num(s.stddev)},
                    {"p5", num(s.p5)},
                    {"p50", num(s.p50)},
                    {"p95", num(s.p95)},
                    {"min", num(s.min)},
                    {"max", num(s.max)}});
    csv << r.config << "," << r.metric << "," << r.runs << "," << s.count << "," << s.mean << ","
        << s.stddev << "," << s.p5 << "," << s.p50 << "," << s.p95 << "," << s.min << "," << s.max
        << "\n";
  }
  nlohmann::json j{{"preset", preset},
                   {"runs_per_config", runs},
                   {"first_seed", seed},
                   {"threads", threads},
                   {"wall_s", o.wallSeconds},
                   {"total_runs", o.totalRuns},
                   {"total_moves", o.totalMoves},
                   {"rows", rows}};
  std::ofstream(dir / "summary.json") << j.dump(2) << "\n";
  if (!csv) throw UsageError("cannot write to --out " + dir.string());
}

}  // namespace

int sweepCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("sweep",
                 "Many seeded coverage runs on all cores, summarised as mean, std, p5, "
                 "p50, p95 per configuration (SPEC §4).");
  args.option("preset", "NAME", "", "laine-fig6 | laine-fig8 | frontier | swinton (required).");
  args.option("runs", "N", "3000 (frontier: 1000, swinton: 20)", "Seeded runs per configuration (swinton: random PDMs per site).");
  args.option("hirise", "FILE", "../shared/dems/mars_gale_hirise_1m/missionDEM.tif",
              "swinton: the HiRISE DEM cropped to its central 150 × 150 m at 0.25 m ('none' = synthetic site only).");
  args.option("configs", "LIST", "all", "swinton: any of lhc_gw_conv,lhc,lawnmower,hybrid.");
  args.option("coordination", "LIST", "timed", "swinton: timed and/or paper; paper rows are named CONFIG+paper.");
  args.option("rovers", "N", "5", "swinton: rovers per mission.");
  args.option("targets", "N", "64", "swinton: route targets per mission.");
  args.option("seed", "S", "1", "First seed; runs use seeds S, S+1, ...");
  args.option("threads", "N", "all cores", "Worker threads.");
  args.option("mission-threads", "N", "1", "swinton: threads each mission plans on (plan_cpu_s then counts the mission's calling thread only).");
  args.option("out", "DIR", "", "Write summary.json and summary.csv into DIR.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (!args.has("preset")) throw UsageError("missing --preset (laine-fig6, laine-fig8, frontier, swinton)");
  const std::string preset = args.str("preset", "");
  if (preset == "swinton") {
    TeamSweepOptions t;
    t.runs = static_cast<int>(args.integer("runs", 20, 1, 100000));
    t.firstSeed = static_cast<std::uint64_t>(args.integer("seed", 1, 0, INT64_MAX));
    t.threads = static_cast<unsigned>(args.integer("threads", hardwareThreads(), 1, 1024));
    t.missionThreads = static_cast<unsigned>(args.integer("mission-threads", 1, 1, 1024));
    t.rovers = static_cast<int>(args.integer("rovers", 5, 1, 64));
    t.targets = static_cast<int>(args.integer("targets", 64, 1, 10000));
    t.hirisePath = args.str("hirise", "../shared/dems/mars_gale_hirise_1m/missionDEM.tif");
    if (t.hirisePath == "none") t.hirisePath.clear();
    if (args.has("coordination")) {
      std::stringstream ss(args.str("coordination", ""));
      for (std::string c; std::getline(ss, c, ',');) t.coordination.push_back(c);
    }
    if (args.has("configs")) {
      std::stringstream ss(args.str("configs", ""));
      for (std::string c; std::getline(ss, c, ',');) t.configs.push_back(c);
    }
    out << "sweep swinton: " << t.runs << " random PDMs per site, " << t.rovers << " rovers, "
        << t.targets << " targets, " << t.threads << " threads\n";
    SweepOutcome o = runTeamSweep(t, out);
    out << "\n" << o.totalRuns << " missions, " << std::fixed << std::setprecision(1) << o.wallSeconds
        << " s wall\n\n";
    printTable(out, o);
    if (args.has("out")) {
      writeFiles(args.str("out", ""), preset, t.runs, t.firstSeed, t.threads, o);
      out << "\nwrote " << args.str("out", "") << "/summary.json and summary.csv\n";
    }
    return 0;
  }
  auto configs = sweepPreset(preset);
  int runs = static_cast<int>(args.integer("runs", presetDefaultRuns(preset), 1, 1000000));
  auto seed = static_cast<std::uint64_t>(args.integer("seed", 1, 0, INT64_MAX));
  unsigned threads = static_cast<unsigned>(args.integer("threads", hardwareThreads(), 1, 1024));

  SweepOutcome o = runSweep(configs, runs, seed, threads);
  out << "sweep " << preset << ": " << configs.size() << " configurations x " << runs
      << " runs = " << o.totalRuns << " runs, " << o.totalMoves << " moves, " << threads
      << " threads, " << std::fixed << std::setprecision(2) << o.wallSeconds << " s wall\n\n";
  printTable(out, o);
  if (args.has("out")) {
    writeFiles(args.str("out", ""), preset, runs, seed, threads, o);
    out << "\nwrote " << args.str("out", "") << "/summary.json and summary.csv\n";
  }
  return 0;
}

}  // namespace rover::cli
