#include "server/studies/study_summary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rover::studies {

namespace {

// rover::summarize over values already sorted, in one pass: the sums run in sorted order, so the
// result does not depend on the order the values were added in.
Summary summarizeSorted(const std::vector<double>& v) {
  Summary s;
  s.count = v.size();
  if (v.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean = s.stddev = s.min = s.max = s.p5 = s.p50 = s.p95 = nan;
    return s;
  }
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  double ss = 0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  s.min = v.front();
  s.max = v.back();
  const auto at = [&](double q) {  // as rover::percentile: linear between order statistics
    const double pos = q / 100.0 * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(pos));
    const std::size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
  };
  s.p5 = at(5);
  s.p50 = at(50);
  s.p95 = at(95);
  return s;
}

}  // namespace

const Summary& SummaryAccumulator::Values::settle() {
  if (!pending.empty()) {
    std::sort(pending.begin(), pending.end());
    const auto middle = static_cast<std::ptrdiff_t>(sorted.size());
    sorted.insert(sorted.end(), pending.begin(), pending.end());
    std::inplace_merge(sorted.begin(), sorted.begin() + middle, sorted.end());
    pending.clear();
    pending.shrink_to_fit();
  }
  if (dirty) {
    figures = summarizeSorted(sorted);
    sum = 0;
    for (double x : sorted) sum += x;
    dirty = false;
  }
  return figures;
}

SummaryAccumulator::SummaryAccumulator(const StudySpec& spec)
    : name_(spec.name), runsTotal_(spec.runCount()), configs_(spec.configurations.size()), seen_(spec.runCount(), false) {
  for (const auto& c : spec.configurations) configNames_.push_back(c.name);
}

std::size_t SummaryAccumulator::metricIndex(const std::string& key) {
  auto [it, fresh] = keyIndex_.try_emplace(key, keys_.size());
  if (fresh) keys_.push_back(key);
  return it->second;
}

void SummaryAccumulator::add(std::int64_t runIndex, int configId, double wallSeconds, double cpuSeconds,
                             const std::vector<std::pair<std::size_t, double>>& metrics) {
  if (configId < 0 || static_cast<std::size_t>(configId) >= configs_.size()) return;
  if (runIndex >= 0 && static_cast<std::size_t>(runIndex) < seen_.size()) {
    if (seen_[static_cast<std::size_t>(runIndex)]) return;
    seen_[static_cast<std::size_t>(runIndex)] = true;
  }
  Config& c = configs_[static_cast<std::size_t>(configId)];
  ++c.runs;
  ++runsDone_;
  c.wall.push(wallSeconds);
  c.cpu.push(cpuSeconds);
  for (const auto& [k, v] : metrics) {
    if (c.metrics.size() <= k) c.metrics.resize(k + 1);
    if (std::isnan(v)) continue;  // stored as NULL: no value
    c.metrics[k].push(v);
  }
}

void SummaryAccumulator::add(const RunRow& row) {
  std::vector<std::pair<std::size_t, double>> metrics;
  metrics.reserve(row.metrics.size());
  for (const auto& [key, value] : row.metrics) metrics.emplace_back(metricIndex(key), value);
  add(row.runIndex, row.configId, row.wallSeconds, row.cpuSeconds, metrics);
}

void SummaryAccumulator::add(const std::vector<RunRow>& rows) {
  for (const auto& r : rows) add(r);
}

StudySummary SummaryAccumulator::summary(bool timing) {
  StudySummary out;
  out.name = name_;
  out.runsTotal = runsTotal_;
  out.runsDone = runsDone_;
  for (std::size_t ci = 0; ci < configs_.size(); ++ci) {
    Config& c = configs_[ci];
    if (c.runs == 0) continue;
    const Summary& wall = c.wall.settle();
    out.wallSeconds += c.wall.sum;
    c.metrics.resize(keys_.size());
    for (std::size_t k = 0; k < keys_.size(); ++k) {
      // A metric a configuration never gave a value (another planner's) is left out of its rows;
      // a level never reached (@ and p_at_ metrics) stays with n = 0.
      const Summary& s = c.metrics[k].settle();
      if (s.count == 0 && keys_[k].find('@') == std::string::npos && keys_[k].rfind("p_at_", 0) != 0) continue;
      out.rows.push_back({configNames_[ci], keys_[k], c.runs, s});
    }
    if (!timing) continue;
    out.rows.push_back({configNames_[ci], "wall_s", c.runs, wall});
    out.rows.push_back({configNames_[ci], "cpu_s", c.runs, c.cpu.settle()});
  }
  return out;
}

}  // namespace rover::studies
