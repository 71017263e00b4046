#include "core/planning/rover_range.hpp"

#include <cstdio>

namespace rover::planning {

namespace {

// "rover 2 drove 24 647 km" style: km from 10 km up, else m; J below 1 MJ, else MJ.
std::string amount(double v, bool energy) {
  char buf[64];
  if (energy) std::snprintf(buf, sizeof buf, v >= 1e6 ? "%.1f MJ" : "%.0f J", v >= 1e6 ? v / 1e6 : v);
  else std::snprintf(buf, sizeof buf, v >= 1e4 ? "%.1f km" : "%.0f m", v >= 1e4 ? v / 1e3 : v);
  return buf;
}

void check(double limit, std::span<const double> values, const char* key, const char* verb, bool energy,
           std::vector<std::string>& out) {
  if (!(limit > 0)) return;
  int past = 0, worst = -1;
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!(values[k] > limit)) continue;
    ++past;
    if (worst < 0 || values[k] > values[static_cast<std::size_t>(worst)]) worst = static_cast<int>(k);
  }
  if (past == 0) return;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%d of %zu rovers %s more than the stated %s %s (rover %d: %s, x%.3g)", past,
                values.size(), verb, key, amount(limit, energy).c_str(), worst + 1,
                amount(values[static_cast<std::size_t>(worst)], energy).c_str(),
                values[static_cast<std::size_t>(worst)] / limit);
  out.push_back(buf);
}

}  // namespace

std::vector<std::string> rangeWarnings(const RoverRange& range, std::span<const double> distanceM,
                                       std::span<const double> energyJ) {
  std::vector<std::string> out;
  check(range.rangeM, distanceM, "rover_range_m", "drove", false, out);
  check(range.energyJ, energyJ, "rover_energy_j", "used", true, out);
  return out;
}

}  // namespace rover::planning
