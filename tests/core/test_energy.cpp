#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "core/coverage/energy.hpp"

using namespace rover::coverage;

TEST_CASE("forward energy on flat ground is rolling resistance over the drive efficiency") {
  EnergyModel e;  // 7 kg, 1.62 m/s², μ 0.15, η 0.7
  CHECK(forwardEnergy(e, 1.0, 0.0) == doctest::Approx(7 * 1.62 * 0.15 / 0.7));
}

TEST_CASE("uphill costs more, steep downhill is clamped at zero (paper 000 eq. 5)") {
  EnergyModel e;
  double up = forwardEnergy(e, 1.0, 0.5);
  double theta = std::atan2(0.5, 1.0);
  CHECK(up == doctest::Approx(7 * 1.62 * (0.15 * std::cos(theta) + std::sin(theta)) *
                              std::hypot(1.0, 0.5) / 0.7));
  CHECK(up > forwardEnergy(e, 1.0, 0.0));
  CHECK(forwardEnergy(e, 1.0, -0.5) == 0.0);  // μ cosθ + sinθ < 0
  CHECK(forwardEnergy(e, 1.0, -0.05) > 0.0);  // gentle downhill still rolls against resistance
}

TEST_CASE("spot-turn energy per radian") {
  EnergyModel e;
  CHECK(turnEnergy(e, 0, 0) == 0.0);
  CHECK(turnEnergy(e, 0, 2) == doctest::Approx(2.0 * std::numbers::pi / 2));
  CHECK(turnEnergy(e, 0, 6) == doctest::Approx(2.0 * std::numbers::pi / 2));
  CHECK(turnEnergy(e, 0, 4) == doctest::Approx(2.0 * std::numbers::pi));
}
