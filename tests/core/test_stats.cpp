#include <doctest/doctest.h>

#include <cmath>

#include "core/common/stats.hpp"

using namespace rover;

TEST_CASE("summary of known values") {
  Summary s = summarize({1, 2, 3, 4, 5});
  CHECK(s.count == 5);
  CHECK(s.mean == doctest::Approx(3));
  CHECK(s.stddev == doctest::Approx(std::sqrt(2.5)));  // sample std
  CHECK(s.p50 == doctest::Approx(3));
  CHECK(s.p5 == doctest::Approx(1.2));  // linear interpolation between order statistics
  CHECK(s.p95 == doctest::Approx(4.8));
  CHECK(s.min == 1);
  CHECK(s.max == 5);
}

TEST_CASE("empty and single-value summaries") {
  CHECK(summarize({}).count == 0);
  CHECK(std::isnan(summarize({}).mean));
  Summary one = summarize({7});
  CHECK(one.stddev == 0);
  CHECK(one.p95 == 7);
}
