#include "core/coverage/energy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include "core/grid/direction.hpp"

namespace rover::coverage {

double forwardEnergy(const EnergyModel& e, double horizontal, double dh) {
  double theta = std::atan2(dh, horizontal);
  double along = std::hypot(horizontal, dh);
  double force = e.massKg * e.gravity * (e.rollingResistance * std::cos(theta) + std::sin(theta));
  return std::max(0.0, force) * along / e.efficiency;
}

double turnEnergy(const EnergyModel& e, int fromDir, int toDir) {
  return e.turnJoulesPerRad * std::abs(turnSteps(fromDir, toDir)) * (std::numbers::pi / 4.0);
}

}  // namespace rover::coverage
