#include "core/team/motion_series.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/coverage/energy.hpp"

namespace rover::team {

namespace {

coverage::EnergyModel energyModel(const RoverModel& model, const DriveEnergy& e) {
  coverage::EnergyModel m;
  m.massKg = model.mass;
  m.gravity = model.gravity;
  m.rollingResistance = e.rollingResistance;
  m.efficiency = e.efficiency;
  return m;
}

double stepEnergy(const coverage::EnergyModel& m, const TrajectorySample& a, const TrajectorySample& b) {
  return coverage::forwardEnergy(m, std::hypot(b.x - a.x, b.y - a.y), b.z - a.z);
}

}  // namespace

double driveEnergyJ(const Trajectory& t, const RoverModel& model, const DriveEnergy& e) {
  const coverage::EnergyModel m = energyModel(model, e);
  double sum = 0;
  for (std::size_t i = 1; i < t.samples.size(); ++i) sum += stepEnergy(m, t.samples[i - 1], t.samples[i]);
  return sum;
}

void motionSeries(const Trajectory& t, std::size_t every, int rover, const RoverModel& model,
                  std::vector<Series>& out, const DriveEnergy& e) {
  every = std::max<std::size_t>(1, every);
  const coverage::EnergyModel m = energyModel(model, e);
  Series speed{"speed_mps_rover_" + std::to_string(rover), "time (s)", "speed_mps", {}, {}};
  Series energy{"energy_j_rover_" + std::to_string(rover), "time (s)", "energy_j", {}, {}};
  const auto& s = t.samples;
  double used = 0;  // J up to sample i
  for (std::size_t i = 0; i < s.size(); i += every) {
    const std::size_t end = std::min(s.size(), i + every);
    double sum = 0;
    for (std::size_t j = i; j < end; ++j) sum += s[j].speed;
    speed.x.push_back(s[i].time);
    speed.y.push_back(sum / static_cast<double>(end - i));
    energy.x.push_back(s[i].time);
    energy.y.push_back(used);
    // On to the next second's first sample (or the last sample).
    for (std::size_t j = i + 1; j <= std::min(end, s.size() - 1); ++j) used += stepEnergy(m, s[j - 1], s[j]);
  }
  // The loop summed every step: the whole trajectory's energy, at its last sample (when that is
  // not a second's first).
  if (!s.empty() && (s.size() - 1) % every != 0) {
    energy.x.push_back(s.back().time);
    energy.y.push_back(used);
    speed.x.push_back(s.back().time);
    speed.y.push_back(s.back().speed);
  }
  out.push_back(std::move(speed));
  out.push_back(std::move(energy));
}

}  // namespace rover::team
