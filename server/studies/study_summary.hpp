#pragma once
// A study's summary table kept up to date run by run (issue 22: recomputing it from the runs table
// took 2.5 s on a 200 k-run study, at every GET). Per configuration and metric the values are kept
// sorted: a batch of runs is merged in (its values sorted, then one linear merge per metric it
// touched), and a row is recomputed only when its values changed, in one linear pass (mean, sample
// standard deviation, min, max, p5/p50/p95 as rover::percentile interpolates).
//
// The figures depend only on the set of runs, never on the order they arrived in (sums run over the
// sorted values), so a summary built batch by batch while a study runs equals the one StudyDb builds
// from its table in one pass (StudyDb::summary uses this class) whichever order the runs came in.
// Memory: one double per run and metric (a 200 k-run study of 17 metrics: 27 MB while it runs).
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "server/studies/study_db.hpp"

namespace rover::studies {

class SummaryAccumulator {
 public:
  explicit SummaryAccumulator(const StudySpec& spec);

  // The index of a metric, added (in the summary's order: first seen first) if new.
  std::size_t metricIndex(const std::string& key);
  // One run: its configuration, timings and metric values by metricIndex (NaN = no value). A run
  // index already added, or a configuration the spec does not have, is ignored (the database
  // keeps the first row of a run too).
  void add(std::int64_t runIndex, int configId, double wallSeconds, double cpuSeconds,
           const std::vector<std::pair<std::size_t, double>>& metrics);
  void add(const RunRow& row);
  void add(const std::vector<RunRow>& rows);

  std::size_t runs() const { return runsDone_; }
  // The table as StudyDb::summary returns it (with timing: wall_s and cpu_s rows).
  StudySummary summary(bool timing = true);

 private:
  struct Values {
    std::vector<double> sorted, pending;  // pending: added since the last summary()
    Summary figures;                      // of `sorted`, valid when !dirty
    double sum = 0;                       // of `sorted` (in sorted order), valid when !dirty
    bool dirty = true;
    void push(double v) {
      pending.push_back(v);
      dirty = true;
    }
    const Summary& settle();
  };
  struct Config {
    std::size_t runs = 0;
    std::vector<Values> metrics;  // by metric index
    Values wall, cpu;
  };
  std::string name_;
  std::size_t runsTotal_ = 0, runsDone_ = 0;
  std::vector<std::string> configNames_;
  std::vector<Config> configs_;
  std::vector<std::string> keys_;
  std::unordered_map<std::string, std::size_t> keyIndex_;
  std::vector<bool> seen_;  // by run index
};

}  // namespace rover::studies
