// A study written as an OMPL benchmark database (server/studies/study_ompl.cpp, issue 28), opened
// with SQLite and checked against the schema OMPL's ompl_benchmark_statistics.py creates and its
// documentation describes ("The benchmark database schema", doc/markdown/benchmark.md): the five
// tables, their fixed columns in order, our metrics as typed run columns, and the row counts
// against the study.
#include <doctest/doctest.h>

#include <sqlite3.h>

#include <set>

#include "api_server.hpp"
#include "server/store/sqlite_stmt.hpp"
#include "server/studies/studies.hpp"

using namespace rover;
using namespace rover::studies;
using nlohmann::json;

namespace {

struct Db {
  sqlite3* db = nullptr;
  explicit Db(const std::string& path) { REQUIRE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK); }
  ~Db() { sqlite3_close(db); }
  long long count(const std::string& sql) {
    store::Stmt s(db, sql.c_str());
    REQUIRE(s.step());
    return s.integer(0);
  }
  // (name, declared type) of each column, in order.
  std::vector<std::pair<std::string, std::string>> columns(const std::string& table) {
    std::vector<std::pair<std::string, std::string>> out;
    store::Stmt s(db, ("PRAGMA table_info(" + table + ")").c_str());
    while (s.step()) out.emplace_back(s.text(1), s.text(2));
    return out;
  }
  std::vector<std::string> names(const std::string& table) {
    std::vector<std::string> out;
    for (const auto& c : columns(table)) out.push_back(c.first);
    return out;
  }
};

std::vector<std::string> head(std::vector<std::string> v, std::size_t n) {
  v.resize(std::min(n, v.size()));
  return v;
}

}  // namespace

TEST_CASE("study export: OMPL's benchmark tables and columns, run counts of the study") {
  test::TempDir tmp;
  // Two worlds (two OMPL experiments), two team sizes × two patterns (four planner configurations,
  // shared by both worlds), two runs each: 16 runs.
  const StudySpec spec = parseStudySpec(json::parse(R"({
    "name": "ompl", "planner": "coverage", "runs": 2, "master_seed": 3,
    "worlds": [{"name": "a", "grid": {"rows": 12, "cols": 12}}, {"name": "b", "grid": {"rows": 14, "cols": 10}}],
    "rovers": [1, 2], "params": {"coverage": 0.9},
    "grid": {"pattern": ["spiral", "boustrophedon"]}, "levels": [0.5, 0.9]
  })"));
  const std::string studyPath = tmp.str("study.sqlite"), omplPath = tmp.str("benchmark.db");
  StudyDb study = StudyDb::open(studyPath);
  RunOptions o;
  o.threads = 1;
  StudyRunner(spec).run(study, o);
  REQUIRE(study.runCount() == 16);
  const OmplCounts n = study.writeOmplBenchmark(omplPath);
  CHECK(n.experiments == 2);
  CHECK(n.plannerConfigs == 4);
  CHECK(n.runs == 16);

  Db db(omplPath);
  // The tables OMPL's script creates, with its columns in its order.
  for (const char* t : {"experiments", "plannerConfigs", "enums", "runs", "progress"})
    CHECK_MESSAGE(db.count(std::string("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = '") + t + "'") == 1, t);
  CHECK(db.names("experiments") == std::vector<std::string>{"id", "name", "totaltime", "timelimit", "memorylimit", "runcount",
                                                             "version", "hostname", "cpuinfo", "date", "seed", "setup"});
  CHECK(db.names("plannerConfigs") == std::vector<std::string>{"id", "name", "settings"});
  CHECK(db.names("enums") == std::vector<std::string>{"name", "value", "description"});
  CHECK(head(db.names("runs"), 3) == std::vector<std::string>{"id", "experimentid", "plannerid"});
  CHECK(head(db.names("progress"), 2) == std::vector<std::string>{"runid", "time"});

  // Runs: one per run of the study, each experiment its world's, joined as Planner Arena joins them.
  CHECK(db.count("SELECT count(*) FROM runs") == static_cast<long long>(spec.runCount()));
  CHECK(db.count("SELECT count(*) FROM plannerConfigs INNER JOIN runs ON plannerConfigs.id = runs.plannerid "
                 "INNER JOIN experiments ON experiments.id = runs.experimentid") == 16);
  CHECK(db.count("SELECT count(*) FROM runs WHERE experimentid = 1") == 8);
  CHECK(db.count("SELECT count(*) FROM runs WHERE experimentid = 2") == 8);
  CHECK(db.count("SELECT min(runcount) FROM experiments") == 2);
  CHECK(db.count("SELECT count(*) FROM experiments WHERE version LIKE 'roverplan %' AND name LIKE 'ompl · %'") == 2);
  CHECK(db.count("SELECT count(DISTINCT plannerid) FROM runs") == 4);

  // Our properties as typed columns: time and the metrics REAL, the stop reason an ENUM of the
  // enums table; every metric of the study is a column.
  std::map<std::string, std::string> types;
  for (const auto& [name, type] : db.columns("runs")) types[name] = type;
  CHECK(types["time"] == "REAL");
  CHECK(types["cpu_time"] == "REAL");
  CHECK(types["seed"] == "INTEGER");
  CHECK(types["status"] == "ENUM");
  CHECK(types["path_length_ratio_at_50pct"] == "REAL");
  CHECK(types["path_length_ratio_at_90pct"] == "REAL");
  CHECK(types["stopped_by_budget"] == "REAL");
  const std::string csvHeader = study.runsCsv().substr(0, study.runsCsv().find('\n'));
  const std::size_t metricCount = static_cast<std::size_t>(std::count(csvHeader.begin(), csvHeader.end(), ',')) + 1 - 11;
  CHECK(types.size() == 3 + 6 + metricCount);
  CHECK(db.count("SELECT count(*) FROM runs INNER JOIN enums ON enums.name = 'status' AND enums.value = runs.status") == 16);

  // The values are the study's: the same metric of the same run.
  {
    Db src(studyPath);
    store::Stmt a(src.db, "SELECT \"path_length_ratio@90%\", wall_s FROM runs WHERE run_index = 5");
    store::Stmt b(db.db, "SELECT path_length_ratio_at_90pct, time FROM runs WHERE run_index = 5 AND id = 6");
    REQUIRE(a.step());
    REQUIRE(b.step());
    CHECK(a.isNull(0) == b.isNull(0));
    if (!a.isNull(0)) CHECK(a.real(0) == b.real(0));
    CHECK(a.real(1) == b.real(1));
  }

  // Progress: every run's coverage curve, its moves as the time key.
  CHECK(db.count("SELECT count(DISTINCT runid) FROM progress") == 16);
  CHECK(db.count("SELECT count(*) FROM progress") == static_cast<long long>(n.progress));
  std::set<std::string> progress;
  for (const auto& c : db.names("progress")) progress.insert(c);
  CHECK(progress == std::set<std::string>{"runid", "time", "moves", "coverage"});
  CHECK(db.count("SELECT count(*) FROM progress WHERE time != moves OR coverage < 0 OR coverage > 1") == 0);

  // Written again, the file is replaced, not appended to.
  study.writeOmplBenchmark(omplPath);
  CHECK(Db(omplPath).count("SELECT count(*) FROM runs") == 16);
}
