#pragma once
// Summary statistics for experiment sweeps (SPEC §4): mean, sample standard deviation and
// percentiles (linear interpolation between order statistics, as numpy's default).
#include <cstddef>
#include <vector>

namespace rover {

struct Summary {
  std::size_t count = 0;
  double mean = 0, stddev = 0, min = 0, max = 0, p5 = 0, p50 = 0, p95 = 0;
};

double percentile(std::vector<double> values, double q);  // q in [0, 100]; empty -> NaN
Summary summarize(const std::vector<double>& values);     // empty -> count 0, NaN fields

}  // namespace rover
