#pragma once
// The study database (issue 12), after OMPL's benchmark database: one SQLite file holds the spec,
// one row per run with every metric as a column, and each run's sampled curves.
//
//   study(id = 1, name, spec TEXT (JSON), version, created_at)
//   configs(config_id PK, name, planner, world, rovers, params TEXT (JSON))
//   runs(run_index PK, config_id, replicate, seed, status,          -- identical in every mode
//        wall_s, cpu_s, host, rank, version,                        -- how and where it ran
//        "<metric>" REAL ...)                                       -- one column per metric
//   metrics(key PK, ord)        -- the metric columns, in the planner's order
//   curves(run_index, curve, x TEXT, y TEXT, PK(run_index, curve))  -- JSON arrays, sampled
//
// Columns are added as metrics appear (ALTER TABLE), so any planner's metrics fit. NaN metrics are
// NULL. WAL mode, synchronous NORMAL, one transaction per batch of runs: a study killed at any
// moment (kill -9) keeps every committed run and resumes with only the missing ones.
// Not thread-safe: one writer (the runner's main thread, MPI rank 0) uses it.
#include <cstdint>
#include <iosfwd>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/stats.hpp"
#include "server/studies/study_spec.hpp"

struct sqlite3;

namespace rover::studies {

struct Curve {
  std::string key;
  std::vector<double> x, y;
};

// One run's result; everything but wallSeconds, cpuSeconds, host and rank is a pure function of
// the spec and the run index.
struct RunRow {
  std::int64_t runIndex = 0;
  int configId = 0;
  std::int64_t replicate = 0;
  std::uint64_t seed = 0;
  std::string status;  // the planner's stop reason
  std::vector<std::pair<std::string, double>> metrics;  // planner order; NaN = no value
  std::vector<Curve> curves;
  double wallSeconds = 0, cpuSeconds = 0;
  std::string host;
  int rank = 0;
};

class SummaryAccumulator;

// Rows written by StudyDb::writeOmplBenchmark, per OMPL table.
struct OmplCounts {
  std::size_t experiments = 0, plannerConfigs = 0, runs = 0, progress = 0, enums = 0;
};

struct SummaryRow {
  std::string config;
  std::string metric;
  std::size_t runs = 0;  // runs of the configuration in the database
  Summary summary;       // over the runs with a value
};

struct StudySummary {
  std::string name;
  std::size_t runsDone = 0, runsTotal = 0;
  double wallSeconds = 0;  // sum of the runs' wall times
  std::vector<SummaryRow> rows;
};

nlohmann::json toJson(const StudySummary& s);

class StudyDb {
 public:
  // Opens or creates the file (":memory:" for none); throws std::runtime_error / StorageFull.
  static StudyDb open(const std::string& path);
  StudyDb(StudyDb&& other) noexcept;
  StudyDb& operator=(StudyDb&&) = delete;
  ~StudyDb();

  // Stores the spec and its configurations in a new database, or checks that the database holds
  // this very spec (same JSON); a different one throws Error(InvalidInput, "spec").
  void attach(const StudySpec& spec);
  bool hasSpec() const;
  nlohmann::json specJson() const;  // throws when the database holds no study

  std::vector<std::int64_t> doneRuns() const;  // ascending
  std::size_t runCount() const;
  // One transaction for the whole batch; a run already stored is left as it is.
  void insert(const std::vector<RunRow>& rows);
  // Adds every run of another study database holding the same spec (shards of one study).
  void mergeFrom(const std::string& path);

  // With `timing`, each configuration also gets wall_s and cpu_s rows (they differ between runs
  // of the same rows: leave them out to compare summaries).
  // Built by a SummaryAccumulator over every run (one pass over the table).
  StudySummary summary(bool timing = true) const;
  // Adds every run of the table to `acc` (a running study's summary starts from what is stored).
  void accumulate(SummaryAccumulator& acc) const;
  // runs as CSV: run_index,config,replicate,seed,status,wall_s,cpu_s,host,rank,<metrics...>
  std::string runsCsv() const;
  void runsCsv(std::ostream& out) const;  // streamed: a big study's CSV need not fit in memory
  // The rows that must be identical in every execution mode (no timing, host or rank), in run
  // order, metrics sorted by key, numbers printed exactly: for identity checks.
  void dump(std::ostream& out) const;
  // The study as an OMPL benchmark database at `path` (replaced), in the schema OMPL's
  // ompl_benchmark_statistics.py writes, so Planner Arena plots it (server/studies/study_ompl.cpp).
  OmplCounts writeOmplBenchmark(const std::string& path) const;

 private:
  explicit StudyDb(sqlite3* db);
  void ensureMetricColumns(const std::vector<RunRow>& rows);
  std::vector<std::string> metricKeys() const;  // in `ord` order
  static std::string metricColumnSql(const std::string& key);  // its runs column, quoted for SQL
  sqlite3* db_;
  std::set<std::string> columns_;
};

}  // namespace rover::studies
