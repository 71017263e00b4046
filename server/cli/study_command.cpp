// `roverplan study run | merge | summary | dump | export` (issue 12): the CLI of the study engine
// (server/studies/studies.hpp).
#include <chrono>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "core/common/parallel.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/study_output.hpp"
#include "server/studies/studies.hpp"

namespace rover::cli {

namespace {

const char* kStudyUsage =
    "usage: roverplan study <run|merge|summary|dump|export> ...\n"
    "  run      (--preset NAME | --spec FILE.json) [--runs N] [--threads N] [--shard K/N] --out FILE.sqlite\n"
    "           (under mpirun -np N: rank 0 writes FILE, every rank runs chunks it hands out)\n"
    "  merge    OUT.sqlite IN.sqlite...   the shards of one study into one database\n"
    "  summary  FILE.sqlite [--json]      mean, std, p5, p50, p95 per configuration and metric\n"
    "  dump     FILE.sqlite               the per-run rows without timing/host/rank (identity checks)\n"
    "  export   FILE.sqlite --ompl OUT.db as an OMPL benchmark database (Planner Arena, ompl_benchmark_statistics.py)\n";

// `K/N`, 0 <= K < N.
std::pair<int, int> parseShard(const std::string& s) {
  const auto slash = s.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    std::size_t a = 0, b = 0;
    const int k = std::stoi(s.substr(0, slash), &a);
    const int n = std::stoi(s.substr(slash + 1), &b);
    if (a != slash || b != s.size() - slash - 1 || n < 1 || k < 0 || k >= n || n > 100000)
      throw std::invalid_argument("range");
    return {k, n};
  } catch (const std::exception&) {
    throw UsageError("invalid value for --shard: '" + s + "' (expected K/N with 0 <= K < N, e.g. $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)");
  }
}

nlohmann::json readSpecFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError("cannot read --spec " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return nlohmann::json::parse(ss.str());
  } catch (const nlohmann::json::exception& e) {
    throw UsageError("--spec " + path + " is not JSON: " + std::string(e.what()).substr(0, 120));
  }
}

// Prints progress at most every 5 s (and at the end).
class ProgressPrinter {
 public:
  explicit ProgressPrinter(std::ostream& out) : out_(out), t0_(std::chrono::steady_clock::now()), last_(t0_) {}
  void operator()(std::size_t done, std::size_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (first_ < 0) first_ = static_cast<long long>(done);
    if (done < total && now - last_ < std::chrono::seconds(5)) return;
    last_ = now;
    const double s = std::chrono::duration<double>(now - t0_).count();
    const double rate = s > 0 ? (static_cast<double>(done) - static_cast<double>(first_)) / s : 0;
    out_ << "  " << done << "/" << total << " runs";
    if (rate > 0 && done < total)
      out_ << ", " << std::fixed << std::setprecision(1) << rate << " runs/s, ETA "
           << std::setprecision(0) << static_cast<double>(total - done) / rate << " s";
    out_ << "\n" << std::flush;
  }

 private:
  std::ostream& out_;
  std::chrono::steady_clock::time_point t0_, last_;
  long long first_ = -1;
};

// The spec of `study run` and `sweep`: a preset or a file, with --runs and --seed applied.
nlohmann::json specFromArgs(const ArgParser& args) {
  if (args.has("preset") == args.has("spec")) throw UsageError("give one of --preset NAME or --spec FILE.json");
  nlohmann::json j;
  if (args.has("preset")) {
    studies::PresetOptions o;
    j = orUsage([&] { return studies::presetSpecJson(args.str("preset", ""), o); });
  } else {
    j = readSpecFile(args.str("spec", ""));
    if (!j.is_object()) throw UsageError("--spec must hold a JSON object");
  }
  if (args.has("runs")) j["runs"] = args.integer("runs", 1, 1, studies::kMaxRuns);
  if (args.has("seed")) j["master_seed"] = args.integer("seed", 1, 0, INT64_MAX);
  return j;
}

int runCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("study run", "Runs a study's missing runs into its SQLite database (resumes a killed study).");
  args.option("preset", "NAME", "", "laine-fig6 | laine-fig8 | frontier | swinton.");
  args.option("spec", "FILE", "", "A study spec (JSON; see server/studies/study_spec.hpp).");
  args.option("runs", "N", "the spec's", "Seeded runs per configuration.");
  args.option("seed", "S", "the spec's", "Master seed (run seeds are derived from it and the run's index).");
  args.option("threads", "N", "all cores (mpirun: cores / ranks per host)", "Worker threads.");
  args.option("shard", "K/N", "0/1", "Only runs with run_index % N == K (job arrays; merge the shards after).");
  args.option("out", "FILE", "", "The study database (SQLite), created or resumed (required).");
  args.flag("quiet", "No progress lines.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (!args.has("out")) throw UsageError("missing --out FILE.sqlite");
  const std::string path = args.str("out", "");
  studies::RunOptions o;
  if (args.has("threads")) o.threads = static_cast<unsigned>(args.integer("threads", 0, 1, 1024));
  if (args.has("shard")) std::tie(o.shardIndex, o.shardCount) = parseShard(args.str("shard", ""));
  ProgressPrinter printer(out);
  studies::ProgressFn progress;
  if (!args.isSet("quiet")) progress = std::ref(printer);

  if (const int ranks = studies::mpiLaunchSize(); ranks > 1) {
    if (!studies::mpiBuilt())
      throw UsageError("launched as " + std::to_string(ranks) +
                       " MPI ranks, but this roverplan was built without MPI (install libopenmpi-dev, rebuild)");
    if (o.shardCount > 1) throw UsageError("--shard and mpirun do not mix: give one of them");
    studies::RunReport report;
    bool root = false;
    const int rc = studies::runStudyMpi([&] { return specFromArgs(args); }, path, o, progress, report, root);
    if (root && rc == 0)
      out << "study: " << report.ran << " runs on " << ranks << " ranks (" << report.alreadyDone << " already in "
          << path << "), " << std::fixed << std::setprecision(2) << report.wallSeconds << " s wall, "
          << std::setprecision(1) << (report.wallSeconds > 0 ? report.ran / report.wallSeconds : 0) << " runs/s\n";
    return rc;
  }

  const studies::StudySpec spec = studies::parseStudySpec(specFromArgs(args));
  const unsigned threads = o.threads > 0 ? o.threads : hardwareThreads();
  studies::StudyDb db = studies::StudyDb::open(path);
  const studies::StudyRunner runner(spec);
  out << "study " << spec.name << ": " << spec.configurations.size() << " configurations x " << spec.runs
      << " runs = " << spec.runCount() << " runs";
  if (o.shardCount > 1) out << ", shard " << o.shardIndex << "/" << o.shardCount;
  out << ", " << threads << " threads\n" << std::flush;
  const studies::RunReport r = runner.run(db, o, progress);
  out << "study: " << r.ran << " runs (" << r.alreadyDone << " already in " << path << "), " << std::fixed
      << std::setprecision(2) << r.wallSeconds << " s wall, " << std::setprecision(1)
      << (r.wallSeconds > 0 ? r.ran / r.wallSeconds : 0) << " runs/s\n";
  return 0;
}

int mergeCommand(const std::vector<std::string>& argv, std::ostream& out) {
  // Any number of inputs: positional arguments without the ArgParser (which counts them).
  if (!argv.empty() && (argv[0] == "--help" || argv[0] == "-h")) {
    out << "usage: roverplan study merge OUT.sqlite IN.sqlite...\n\nMerges the shard databases of one study "
           "into OUT (created, or extended when it holds the same study); a database of another spec is refused.\n";
    return 0;
  }
  const auto& p = argv;
  if (p.size() < 2) throw UsageError("usage: roverplan study merge OUT.sqlite IN.sqlite...");
  for (const auto& a : p)
    if (a.rfind("--", 0) == 0) throw UsageError("unknown option " + a);
  for (std::size_t i = 1; i < p.size(); ++i)
    if (!std::filesystem::exists(p[i])) throw UsageError("no such study database: " + p[i]);
  // Every input must hold the same spec (and OUT, when it holds one), checked before anything is merged.
  studies::StudyDb db = studies::StudyDb::open(p[0]);
  std::string spec = db.hasSpec() ? db.specJson().dump() : "";
  for (std::size_t i = 1; i < p.size(); ++i) {
    studies::StudyDb in = studies::StudyDb::open(p[i]);
    if (!in.hasSpec()) throw UsageError(p[i] + " holds no study");
    const std::string s = in.specJson().dump();
    if (spec.empty()) spec = s;
    if (s != spec) throw UsageError(p[i] + " holds a different study (its spec differs from " + (i > 1 ? p[1] : p[0]) + "'s); nothing merged");
  }
  for (std::size_t i = 1; i < p.size(); ++i) db.mergeFrom(p[i]);
  const auto s = db.summary();
  out << "merged " << p.size() - 1 << " databases into " << p[0] << ": " << s.runsDone << "/" << s.runsTotal
      << " runs\n";
  return 0;
}

studies::StudyDb openExisting(const std::string& path) {
  if (!std::filesystem::exists(path)) throw UsageError("no such study database: " + path);
  studies::StudyDb db = studies::StudyDb::open(path);
  if (!db.hasSpec()) throw UsageError(path + " holds no study");
  return db;
}

int summaryCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("study summary", "Per configuration and metric: n, mean, std, p5, p50, p95.");
  args.positional("FILE", "A study database.");
  args.flag("json", "Print JSON instead of the table.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (args.positionals().size() != 1) throw UsageError("usage: roverplan study summary FILE.sqlite [--json]");
  const auto s = openExisting(args.positionals()[0]).summary();
  if (args.isSet("json")) {
    out << studies::toJson(s).dump(2) << "\n";
    return 0;
  }
  out << "study " << s.name << ": " << s.runsDone << "/" << s.runsTotal << " runs\n\n";
  printSummaryTable(out, s);
  return 0;
}

int dumpCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("study dump", "The per-run rows without wall/cpu time, host and rank, for identity checks.");
  args.positional("FILE", "A study database.");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (args.positionals().size() != 1) throw UsageError("usage: roverplan study dump FILE.sqlite");
  openExisting(args.positionals()[0]).dump(out);
  return 0;
}

int exportCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser args("study export", "Writes a study database as an OMPL benchmark database: the tables and columns "
                                 "OMPL's ompl_benchmark_statistics.py writes (experiments, plannerConfigs, enums, "
                                 "runs, progress), the metrics as run columns, for Planner Arena.");
  args.positional("FILE", "A study database.");
  args.option("ompl", "OUT.db", "", "The OMPL benchmark database to write (replaced) (required).");
  if (!args.parse(argv)) {
    out << args.help();
    return 0;
  }
  if (args.positionals().size() != 1 || !args.has("ompl"))
    throw UsageError("usage: roverplan study export FILE.sqlite --ompl OUT.db");
  const std::string target = args.str("ompl", "");
  const studies::OmplCounts n = openExisting(args.positionals()[0]).writeOmplBenchmark(target);
  out << "wrote " << target << ": " << n.experiments << " experiments, " << n.plannerConfigs << " planner configs, "
      << n.runs << " runs, " << n.progress << " progress rows\n";
  return 0;
}

}  // namespace

int studyCommand(const std::vector<std::string>& argv, std::ostream& out) {
  if (argv.empty() || argv[0] == "--help" || argv[0] == "-h") {
    out << kStudyUsage;
    if (argv.empty()) throw UsageError("missing subcommand (run, merge, summary, dump, export)");
    return 0;
  }
  const std::vector<std::string> rest(argv.begin() + 1, argv.end());
  if (argv[0] == "run") return runCommand(rest, out);
  if (argv[0] == "merge") return mergeCommand(rest, out);
  if (argv[0] == "summary") return summaryCommand(rest, out);
  if (argv[0] == "dump") return dumpCommand(rest, out);
  if (argv[0] == "export") return exportCommand(rest, out);
  throw UsageError("unknown subcommand '" + argv[0] + "' (run, merge, summary, dump, export)");
}

}  // namespace rover::cli
