// Speed and drive energy against mission time (core/team/motion_series.hpp): one point a second,
// at the pitch/roll series' times, energy by paper 000 eq. 5 with the team rover's mass and gravity.
#include <doctest/doctest.h>

#include <cmath>

#include "core/team/motion_series.hpp"

using namespace rover;
using namespace rover::team;

namespace {

// 10 Hz samples: 2.5 s at `speed` along x on flat ground, then 2 s climbing 1 cm a sample.
Trajectory drawnTrajectory(double speed) {
  Trajectory t;
  double x = 0, z = 0;
  for (int k = 0; k <= 45; ++k) {
    TrajectorySample s;
    s.time = 0.1 * k;
    s.x = x;
    s.z = z;
    s.speed = k < 25 ? speed : speed / 2;
    t.samples.push_back(s);
    x += 0.1 * s.speed;
    if (k >= 25) z += 0.01;
  }
  return t;
}

const Series& find(const std::vector<Series>& all, const std::string& key) {
  for (const auto& s : all)
    if (s.key == key) return s;
  FAIL("no series " << key);
  return all.front();
}

}  // namespace

TEST_CASE("motion series: the mean speed of each second and the energy used so far, at each second's first sample") {
  const Trajectory t = drawnTrajectory(0.3);
  RoverModel model;  // 1.5 kg, Mars gravity
  std::vector<Series> out;
  motionSeries(t, 10, 1, model, out);
  REQUIRE(out.size() == 2);
  const Series& speed = find(out, "speed_mps_rover_1");
  const Series& energy = find(out, "energy_j_rover_1");
  CHECK(speed.xLabel == "time (s)");
  // Seconds 0..4 (samples 0, 10, 20, 30, 40) and the last sample (4.5 s).
  REQUIRE(speed.x.size() == 6);
  REQUIRE(energy.x.size() == 6);
  CHECK(speed.x[1] == doctest::Approx(1.0));
  CHECK(energy.x[5] == doctest::Approx(4.5));
  CHECK(speed.y[0] == doctest::Approx(0.3));
  CHECK(speed.y[2] == doctest::Approx((5 * 0.3 + 5 * 0.15) / 10));  // samples 20..29
  CHECK(speed.y[3] == doctest::Approx(0.15));
  // Flat first second: m·g·μ·s/η with s = 10 × 0.03 m (paper 000 eq. 5, μ 0.15, η 0.7).
  CHECK(energy.y[0] == 0);
  CHECK(energy.y[1] == doctest::Approx(1.5 * 3.71 * 0.15 * 0.3 / 0.7));
  for (std::size_t i = 1; i < energy.y.size(); ++i) CHECK(energy.y[i] >= energy.y[i - 1]);
  // The last point is the whole trajectory's energy; the climb costs more than flat ground.
  CHECK(energy.y.back() == doctest::Approx(driveEnergyJ(t, model)));
  const double flat = 1.5 * 3.71 * 0.15 * (25 * 0.03 + 20 * 0.015) / 0.7;
  CHECK(energy.y.back() > flat);
}

TEST_CASE("motion series: mass and gravity scale the energy, downhill recovers nothing") {
  Trajectory t = drawnTrajectory(0.3);
  RoverModel light, heavy;
  heavy.mass = 3.0;
  CHECK(driveEnergyJ(t, heavy) == doctest::Approx(2 * driveEnergyJ(t, light)));
  for (auto& s : t.samples) s.z = -s.z;  // the climb becomes a descent steeper than μ: 0 J
  const double flatPart = 1.5 * 3.71 * 0.15 * (25 * 0.03) / 0.7;
  CHECK(driveEnergyJ(t, light) == doctest::Approx(flatPart));
  std::vector<Series> none;
  motionSeries(Trajectory{}, 10, 0, light, none);
  CHECK(none.size() == 2);
  CHECK(none[0].x.empty());
}
