#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

#include <nlohmann/json.hpp>

#include "core/common/parallel.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/sweep.hpp"

namespace rover::cli {

namespace {

void printTable(std::ostream& out, const SweepOutcome& o) {
  out << std::left << std::setw(24) << "config" << std::setw(26) << "metric" << std::right
      << std::setw(6) << "n" << std::setw(10) << "mean" << std::setw(10) << "std" << std::setw(10)
      << "p5" << std::setw(10) << "p50" << std::setw(10) << "p95"
      << "\n";
  out << std::fixed << std::setprecision(4);
  std::string last;
  for (const auto& r : o.rows) {
    if (!last.empty() && r.config != last) out << "\n";
    last = r.config;
    out << std::left << std::setw(24) << r.config << std::setw(26) << r.metric << std::right
        << std::setw(6) << r.summary.count << std::setw(10) << r.summary.mean << std::setw(10)
        << r.summary.stddev << std::setw(10) << r.summary.p5 << std::setw(10) << r.summary.p50
        << std::setw(10) << r.summary.p95 << "\n";
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
  args.option("preset", "NAME", "", "laine-fig6 | laine-fig8 | frontier (required).");
  args.option("runs", "N", "3000 (frontier: 1000)", "Seeded runs per configuration.");
  args.option("seed", "S", "1", "First seed; runs use seeds S, S+1, ...");
  args.option("threads", "N", "all cores", "Worker threads.");
  args.option("out", "DIR", "", "Write summary.json and summary.csv into DIR.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (!args.has("preset")) throw UsageError("missing --preset (laine-fig6, laine-fig8, frontier)");
  const std::string preset = args.str("preset", "");
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
