// roverplan's subcommands called in-process: coverage (--json shape, determinism, usage errors that
// name the option, --help), sweep (summary files) and bench.
#include <doctest/doctest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/parallel.hpp"
#include "core/common/params.hpp"
#include "core/coverage/coverage_params.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/coverage_options.hpp"

using nlohmann::json;
using rover::cli::UsageError;
using Args = std::vector<std::string>;

namespace {

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// Runs `coverage` with args and returns its stdout; the status must be 0.
std::string runCoverage(const Args& args) {
  std::ostringstream out;
  int status = rover::cli::coverageCommand(args, out);
  CHECK(status == 0);
  return out.str();
}

json runCoverageJson(Args args) {
  args.push_back("--json");
  const std::string text = runCoverage(args);
  REQUIRE(!text.empty());
  CHECK(text.back() == '\n');
  // One JSON object on one line.
  CHECK(text.find('\n') == text.size() - 1);
  json j = json::parse(text);
  REQUIRE(j.is_object());
  return j;
}

// The message of the UsageError thrown by `coverage args` ("" if none).
std::string coverageUsageError(const Args& args) {
  std::ostringstream out;
  try {
    rover::cli::coverageCommand(args, out);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

// A fresh directory under the system temp dir, removed when the guard goes out of scope.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static std::atomic<int> counter{0};
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    path = std::filesystem::temp_directory_path() /
           ("rover_test_server_" + std::to_string(stamp) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

std::string readFile(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const Args kSmall{"--rows", "20", "--cols", "20"};

Args small(std::initializer_list<std::string> extra) {
  Args a = kSmall;
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

}  // namespace

TEST_CASE("coverage --json: metrics, one path per rover, the coverage curve") {
  json j = runCoverageJson(small({"--seed", "3", "--rovers", "3"}));
  CHECK(j["planner"] == "coverage");
  CHECK(j["stop_reason"].is_string());
  CHECK(j["cancelled"] == false);

  REQUIRE(j["metrics"].is_object());
  for (const char* key : {"coverage", "moves", "makespan", "path_length_ratio", "distance_m",
                          "energy_j", "max_pitch_deg", "revisits", "unreachable_cells"}) {
    CAPTURE(key);
    REQUIRE(j["metrics"].contains(key));
    CHECK(j["metrics"][key].is_number());
    CHECK(j["metrics"][key].get<double>() >= 0.0);
  }
  const json& m = j["metrics"];
  CHECK(m["coverage"].get<double>() > 0.0);
  CHECK(m["coverage"].get<double>() <= 1.0);
  CHECK(m["moves"].get<double>() > 0.0);
  CHECK(m["makespan"].get<double>() <= m["moves"].get<double>());
  CHECK(m["distance_m"].get<double>() > 0.0);

  REQUIRE(j["rovers"].is_array());
  REQUIRE(j["rovers"].size() == 3);
  double movesSum = 0;
  for (std::size_t k = 0; k < j["rovers"].size(); ++k) {
    CAPTURE(k);
    const json& r = j["rovers"][k];
    CHECK(r["rover"] == k);
    REQUIRE(r["path"].is_array());
    CHECK_FALSE(r["path"].empty());
    for (const auto& p : r["path"]) {
      REQUIRE(p.is_array());
      REQUIRE(p.size() == 2);
      // Cell centres of a 20 × 20 grid of 1 m cells.
      CHECK(p[0].get<double>() >= 0.0);
      CHECK(p[0].get<double>() <= 20.0);
      CHECK(p[1].get<double>() >= 0.0);
      CHECK(p[1].get<double>() <= 20.0);
    }
    movesSum += r["metrics"]["moves"].get<double>();
  }
  CHECK(movesSum == doctest::Approx(m["moves"].get<double>()));

  REQUIRE(j["series"].is_object());
  REQUIRE(j["series"].contains("coverage_vs_moves"));
  const json& curve = j["series"]["coverage_vs_moves"];
  REQUIRE(curve["x"].is_array());
  REQUIRE(curve["y"].is_array());
  CHECK_FALSE(curve["x"].empty());
  CHECK(curve["x"].size() == curve["y"].size());

  // The world and the resolved parameters are echoed.
  CHECK(j["world"]["rows"] == 20);
  CHECK(j["world"]["cols"] == 20);
  CHECK(j["world"]["seed"] == 3);
  CHECK(j["starts"].size() == 3);
  CHECK(j["params"]["pattern"] == "spiral");
  CHECK(j["params"]["mode"] == "overlap");
}

TEST_CASE("coverage --json with the default world and one rover") {
  json j = runCoverageJson({"--seed", "5"});
  CHECK(j["world"]["rows"] == 60);
  CHECK(j["world"]["cols"] == 60);
  REQUIRE(j["rovers"].size() == 1);
  CHECK_FALSE(j["rovers"][0]["path"].empty());
  CHECK(j["metrics"]["coverage"].get<double>() > 0.5);
}

TEST_CASE("coverage: the same seed gives byte-identical output, another seed differs") {
  const Args a = small({"--seed", "11", "--rovers", "2"});
  const Args b = small({"--seed", "12", "--rovers", "2"});
  Args aj = a, bj = b;
  aj.push_back("--json");
  bj.push_back("--json");
  const std::string first = runCoverage(aj);
  const std::string second = runCoverage(aj);
  CHECK(first == second);
  CHECK(first != runCoverage(bj));
  // The readable summary too.
  CHECK(runCoverage(a) == runCoverage(a));
  CHECK(runCoverage(a) != runCoverage(b));
}

TEST_CASE("coverage: the readable summary") {
  const std::string text = runCoverage(small({"--seed", "2"}));
  CHECK(contains(text, "world      20 x 20 cells"));
  CHECK(contains(text, "seed 2"));
  CHECK(contains(text, "planner    spiral"));
  CHECK(contains(text, "path length ratio"));
  CHECK(contains(text, "coverage   "));
  CHECK(contains(text, "energy"));
  const std::string team = runCoverage(
      small({"--rovers", "2", "--mode", "voronoi", "--pattern", "boustrophedon", "--frontier"}));
  CHECK(contains(team, "boustrophedon + frontier, 2 rover(s), voronoi"));
}

TEST_CASE("coverage: bad values are usage errors naming the CLI option") {
  struct Case {
    Args args;
    std::string option;
  };
  const std::vector<Case> cases{
      {{"--sense", "3"}, "--sense"},
      {{"--sense", "two"}, "--sense"},
      {{"--coverage", "0"}, "--coverage"},
      {{"--coverage", "1.5"}, "--coverage"},
      {{"--alpha", "0.5", "--beta", "0.2"}, "--beta"},
      {{"--alpha", "1.5"}, "--alpha"},
      {{"--pattern", "zigzag"}, "--pattern"},
      {{"--mode", "x"}, "--mode"},
      {{"--rovers", "0"}, "--rovers"},
      {{"--rovers", "65"}, "--rovers"},
      {{"--cost-table", "1,2"}, "--cost-table"},
      {{"--cost-table", "1,x"}, "--cost-table"},
      {{"--cost-table", "1,2,3,4,5,4,3,2"}, "--cost-table"},  // symmetric turns
      {{"--pattern", "spiral", "--cost-table", "1,2,3,4,5,6,7,8"}, "--cost-table"},
      {{"--max-steps", "-1"}, "--max-steps"},
      {{"--mc-visited", "1.0"}, "--mc-visited"},
      {{"--rover-mass", "0"}, "--rover-mass"},
      {{"--rows", "abc"}, "--rows"},
      {{"--rows", "1"}, "--rows"},
      {{"--cell", "0"}, "--cell"},
      {{"--obstacles", "0.95"}, "--obstacles"},
      {{"--seed", "-1"}, "--seed"},
      {{"--frobnicate"}, "--frobnicate"},
      {{"--json=1"}, "--json"},
      {{"--frontier=yes"}, "--frontier"},
  };
  for (const auto& c : cases) {
    std::string joined;
    for (const auto& a : c.args) joined += a + " ";
    CAPTURE(joined);
    const Args args = small({});
    Args full = args;
    full.insert(full.end(), c.args.begin(), c.args.end());
    const std::string msg = coverageUsageError(full);
    CHECK_FALSE(msg.empty());
    CHECK(contains(msg, c.option));
    // One line, as main prints it.
    CHECK(msg.find('\n') == std::string::npos);
  }
}

TEST_CASE("coverage: giving one of alpha and beta implies the other") {
  json j = runCoverageJson(small({"--beta", "0.7"}));
  CHECK(j["params"]["beta"].get<double>() == doctest::Approx(0.7));
  CHECK(j["params"]["alpha"].get<double>() == doctest::Approx(0.3));

  json k = runCoverageJson(small({"--alpha", "0.4"}));
  CHECK(k["params"]["alpha"].get<double>() == doctest::Approx(0.4));
  CHECK(k["params"]["beta"].get<double>() == doctest::Approx(0.6));

  json both = runCoverageJson(small({"--alpha", "0.25", "--beta", "0.75"}));
  CHECK(both["params"]["alpha"].get<double>() == doctest::Approx(0.25));
  CHECK(both["params"]["beta"].get<double>() == doctest::Approx(0.75));
}

TEST_CASE("coverage: options reach the planner") {
  json j = runCoverageJson(small({"--pattern", "boustrophedon", "--sense", "2", "--circumnavigate",
                                  "--frontier", "--coverage", "0.5", "--mode", "voronoi",
                                  "--rovers", "2", "--obstacles", "0", "--cell", "2"}));
  CHECK(j["params"]["pattern"] == "boustrophedon");
  CHECK(j["params"]["sense_radius"] == 2);
  CHECK(j["params"]["circumnavigate"] == true);
  CHECK(j["params"]["frontier"] == true);
  CHECK(j["params"]["coverage"].get<double>() == doctest::Approx(0.5));
  CHECK(j["params"]["mode"] == "voronoi");
  CHECK(j["world"]["obstacles"] == 0);
  CHECK(j["world"]["cell_size_m"].get<double>() == doctest::Approx(2.0));
  CHECK(j["rovers"].size() == 2);

  // A cost table alone selects the custom pattern.
  json c = runCoverageJson(small({"--cost-table", "1,2,3,4,5,6,7,8"}));
  CHECK(c["params"]["pattern"] == "custom");
  REQUIRE(c["params"]["cost_table"].size() == 8);
  CHECK(c["params"]["cost_table"][4].get<double>() == doctest::Approx(5.0));

  // The step budget stops the run.
  json s = runCoverageJson(small({"--max-steps", "5"}));
  CHECK(s["params"]["max_steps"] == 5);
  CHECK(s["stop_reason"] == "step_budget");
  CHECK(s["metrics"]["steps"].get<double>() <= 5.0);
}

TEST_CASE("coverage --help lists every option and returns 0") {
  std::ostringstream out;
  CHECK(rover::cli::coverageCommand({"--help"}, out) == 0);
  const std::string h = out.str();
  CHECK(contains(h, "usage: roverplan coverage"));
  for (const char* o : {"--rows", "--cols", "--cell", "--obstacles", "--seed", "--rovers",
                        "--no-sealed", "--json", "--help"}) {
    CAPTURE(o);
    CHECK(contains(h, o));
  }
  // Every planner parameter, under its CLI name.
  for (const auto& info : rover::coverage::coverageParamTable().infos()) {
    const std::string option = "--" + rover::cli::optionForParam(info.key);
    CAPTURE(option);
    CHECK(contains(h, option));
    if (info.type != rover::ParamType::Bool && info.type != rover::ParamType::RealList) {
      CHECK(contains(h, "(default: " + rover::paramToString(info.defaultValue) + ")"));
    }
  }
  for (const char* o : {"--mode", "--pattern", "--circumnavigate", "--frontier", "--sense",
                        "--coverage", "--alpha", "--beta", "--max-steps", "--cost-table"}) {
    CAPTURE(o);
    CHECK(contains(h, o));
  }
  CHECK(contains(h, "--rows N\n"));
  CHECK(contains(h, "(default: 60)"));
  CHECK(contains(h, "spiral|boustrophedon|custom"));
  // --help wins even after other options, and nothing is run.
  std::ostringstream again;
  CHECK(rover::cli::coverageCommand({"--rows", "20", "--help"}, again) == 0);
  CHECK(again.str() == h);
}

TEST_CASE("optionForParam maps planner keys to CLI option names") {
  CHECK(rover::cli::optionForParam("sense_radius") == "sense");
  CHECK(rover::cli::optionForParam("max_steps") == "max-steps");
  CHECK(rover::cli::optionForParam("cost_table") == "cost-table");
  CHECK(rover::cli::optionForParam("beta") == "beta");
}

TEST_CASE("throwAsUsage re-says a core error in terms of the option") {
  try {
    rover::cli::throwAsUsage(rover::Error(rover::ErrorCode::InvalidParameter, "sense_radius",
                                          "sense_radius: must be in [1, 2], got 3"));
  } catch (const UsageError& e) {
    CHECK(std::string(e.what()) == "invalid value for --sense: must be in [1, 2], got 3");
  }
  try {
    rover::cli::throwAsUsage(rover::Error(rover::ErrorCode::InvalidInput, "", "no free cell"));
  } catch (const UsageError& e) {
    CHECK(std::string(e.what()) == "no free cell");
  }
}

TEST_CASE("sweep --preset laine-fig6 writes summary.json and summary.csv") {
  TempDir dir;
  std::ostringstream out;
  REQUIRE(rover::cli::sweepCommand({"--preset", "laine-fig6", "--runs", "3", "--threads", "2",
                                    "--out", dir.path.string()},
                                   out) == 0);
  const std::string text = out.str();
  CHECK(contains(text, "sweep laine-fig6: 4 configurations x 3 runs = 12 runs"));
  CHECK(contains(text, "2 threads"));
  CHECK(contains(text, "summary.json"));

  const auto jsonPath = dir.path / "summary.json";
  const auto csvPath = dir.path / "summary.csv";
  REQUIRE(std::filesystem::exists(jsonPath));
  REQUIRE(std::filesystem::exists(csvPath));

  json j = json::parse(readFile(jsonPath));
  CHECK(j["preset"] == "laine-fig6");
  CHECK(j["runs_per_config"] == 3);
  CHECK(j["threads"] == 2);
  CHECK(j["total_runs"] == 12);
  CHECK(j["total_moves"].get<double>() > 0);
  REQUIRE(j["rows"].is_array());
  REQUIRE_FALSE(j["rows"].empty());
  std::vector<std::string> configs;
  bool sawRatio = false;
  for (const auto& r : j["rows"]) {
    for (const char* key :
         {"config", "metric", "runs", "n", "mean", "std", "p5", "p50", "p95", "min", "max"})
      CHECK(r.contains(key));
    CHECK(r["runs"] == 3);
    CHECK(r["n"].get<int>() <= 3);
    const std::string c = r["config"].get<std::string>();
    if (configs.empty() || configs.back() != c) configs.push_back(c);
    if (r["metric"] == "path_length_ratio") {
      sawRatio = true;
      CHECK(r["n"] == 3);
      CHECK(r["mean"].get<double>() >= 1.0);
    }
  }
  CHECK(sawRatio);
  CHECK(configs ==
        std::vector<std::string>{"spiral", "spiral+circ", "boustrophedon", "boustrophedon+circ"});

  const std::string csv = readFile(csvPath);
  CHECK(csv.rfind("config,metric", 0) == 0);
  CHECK(csv.rfind("config,metric,runs,n,mean,std,p5,p50,p95,min,max\n", 0) == 0);
  // One CSV line per JSON row, after the header.
  std::size_t lines = 0;
  for (char ch : csv) lines += ch == '\n';
  CHECK(lines == j["rows"].size() + 1);
}

TEST_CASE("sweep results do not depend on the thread count") {
  TempDir one, two;
  std::ostringstream o1, o2;
  REQUIRE(rover::cli::sweepCommand({"--preset", "frontier", "--runs", "3", "--threads", "1",
                                    "--seed", "7", "--out", one.path.string()},
                                   o1) == 0);
  REQUIRE(rover::cli::sweepCommand({"--preset", "frontier", "--runs", "3", "--threads", "2",
                                    "--seed", "7", "--out", two.path.string()},
                                   o2) == 0);
  CHECK(readFile(one.path / "summary.csv") == readFile(two.path / "summary.csv"));
  json a = json::parse(readFile(one.path / "summary.json"));
  json b = json::parse(readFile(two.path / "summary.json"));
  CHECK(a["rows"] == b["rows"]);
  CHECK(a["master_seed"] == 7);
}

TEST_CASE("sweep usage errors") {
  std::ostringstream out;
  CHECK_THROWS_WITH_AS(rover::cli::sweepCommand({"--preset", "nope", "--runs", "1"}, out),
                       "unknown preset 'nope' (laine-fig6, laine-fig8, frontier, swinton)", UsageError);
  try {
    rover::cli::sweepCommand({"--runs", "1"}, out);
    FAIL("sweep without --preset ran");
  } catch (const UsageError& e) {
    CHECK(contains(e.what(), "--preset"));
  }
  try {
    rover::cli::sweepCommand({"--preset", "frontier", "--runs", "0"}, out);
    FAIL("sweep --runs 0 ran");
  } catch (const UsageError& e) {
    CHECK(contains(e.what(), "--runs"));
  }
  try {
    rover::cli::sweepCommand({"--preset", "frontier", "--runs", "1", "--threads", "0"}, out);
    FAIL("sweep --threads 0 ran");
  } catch (const UsageError& e) {
    CHECK(contains(e.what(), "--threads"));
  }
  CHECK(out.str().empty());
}

TEST_CASE("sweep --help") {
  std::ostringstream out;
  CHECK(rover::cli::sweepCommand({"--help"}, out) == 0);
  for (const char* o : {"--preset", "--runs", "--seed", "--threads", "--out"}) {
    CAPTURE(o);
    CHECK(contains(out.str(), o));
  }
}

TEST_CASE("bench coverage prints runs/s for each variant") {
  std::ostringstream out;
  REQUIRE(rover::cli::benchCommand({"coverage", "--runs", "5"}, out) == 0);
  std::istringstream lines(out.str());
  std::vector<std::string> all;
  for (std::string line; std::getline(lines, line);) all.push_back(line);
  REQUIRE(all.size() == 6);
  CHECK(contains(all[0], "5 seeded runs"));
  CHECK(contains(all[1], "runs/s"));
  CHECK(contains(all[1], "moves/s"));
  CHECK(all[2].rfind("spiral ", 0) == 0);
  CHECK(all[3].rfind("spiral ", 0) == 0);
  CHECK(all[4].rfind("spiral+frontier", 0) == 0);
  CHECK(all[5].rfind("spiral+frontier", 0) == 0);
  // The second line of each variant runs on all cores and reports the speed-up.
  if (rover::hardwareThreads() > 1) {
    CHECK(contains(all[3], "speed-up x"));
    CHECK(contains(all[5], "speed-up x"));
  }
}

TEST_CASE("bench usage errors") {
  std::ostringstream out;
  CHECK_THROWS_WITH_AS(rover::cli::benchCommand({}, out), "missing argument TARGET", UsageError);
  CHECK_THROWS_WITH_AS(rover::cli::benchCommand({"planner"}, out),
                       "unknown benchmark 'planner' (coverage, mission, routes, localisation)", UsageError);
  try {
    rover::cli::benchCommand({"coverage", "--runs", "0"}, out);
    FAIL("bench --runs 0 ran");
  } catch (const UsageError& e) {
    CHECK(contains(e.what(), "--runs"));
  }
  // bench routes: the paired comparison's lines, with the same figures on a second run.
  std::ostringstream routes, again;
  CHECK(rover::cli::benchCommand({"routes", "--runs", "2"}, routes) == 0);
  CHECK(contains(routes.str(), "synthetic Mars 600x600"));
  CHECK(contains(routes.str(), "paired ratio   geometric mean x"));
  CHECK(contains(routes.str(), "route length   LHC_GW_CONV"));
  CHECK(rover::cli::benchCommand({"routes", "--runs", "2"}, again) == 0);
  auto figures = [](const std::string& s) { return s.substr(0, s.find("  compute")); };
  CHECK(figures(routes.str()) == figures(again.str()));
  std::ostringstream help;
  CHECK(rover::cli::benchCommand({"--help"}, help) == 0);
  CHECK(contains(help.str(), "--runs"));
  CHECK(contains(help.str(), "TARGET"));
}

TEST_CASE("an out-of-range --beta alone is reported as --beta, not as the implied --alpha") {
  std::ostringstream out;
  CHECK_THROWS_WITH_AS(rover::cli::coverageCommand({"--beta", "1.5"}, out),
                       "invalid value for --beta: must be in [0, 1], got 1.5",
                       rover::cli::UsageError);
}

TEST_CASE("coverage with odometry noise: the truth line, and --json's true and believed paths") {
  const std::string text = runCoverage({"--rows", "20", "--cols", "20", "--odometry-noise", "5",
                                        "--heading-noise", "1", "--loop-closure"});
  CHECK(contains(text, "truth      coverage "));
  CHECK(contains(text, "localisation MAE "));
  CHECK_FALSE(contains(runCoverage({"--rows", "20", "--cols", "20"}), "truth "));
  json j = runCoverageJson({"--rows", "20", "--cols", "20", "--odometry-noise", "5", "--noise-seed", "4"});
  CHECK(j["metrics"].contains("true_coverage"));
  CHECK(j["params"]["noise_seed"] == 4);
  CHECK(j["rovers"][0]["believed_path"].size() == j["rovers"][0]["path"].size());
  CHECK(contains(coverageUsageError({"--heading-noise", "90"}), "--heading-noise"));
}

TEST_CASE("bench localisation prints MAE and true coverage at the believed stop per level") {
  std::ostringstream out;
  REQUIRE(rover::cli::benchCommand({"localisation", "--runs", "4", "--sizes", "5", "--levels", "0,2"}, out) == 0);
  const std::string text = out.str();
  CHECK(contains(text, "field 5 x 5 m"));
  CHECK(contains(text, "true @ goal"));
  // Zero noise: no error, true coverage = believed.
  CHECK(contains(text, "0.000  0.000   0.000   off      0.000"));
  CHECK(contains(text, "2.000  8.000   2.000   on "));
}
