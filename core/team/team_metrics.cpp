#include "core/team/team_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "core/team/separation.hpp"

namespace rover::team {

namespace {

// Marks the map cells whose centre is within `radius` of p; adds the newly marked mass.
class DiscMarker {
 public:
  DiscMarker(const Raster<float>& pdm, double radius)
      : pdm_(pdm), seen_(static_cast<std::size_t>(pdm.geometry.cellCount()), 0), r_(radius) {}
  void mark(const Eigen::Vector2d& p) {
    const GridGeometry& g = pdm_.geometry;
    const double top = g.heightMetres();
    const int c0 = std::max(0, static_cast<int>(std::floor((p.x() - r_) / g.cellWidth)));
    const int c1 = std::min(g.cols - 1, static_cast<int>(std::floor((p.x() + r_) / g.cellWidth)));
    const int r0 = std::max(0, static_cast<int>(std::floor((top - p.y() - r_) / g.cellHeight)));
    const int r1 = std::min(g.rows - 1, static_cast<int>(std::floor((top - p.y() + r_) / g.cellHeight)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const int i = g.index(r, c);
        if (seen_[i] || (cellToLocal(g, {r, c}) - p).squaredNorm() > r_ * r_) continue;
        seen_[i] = 1;
        const float m = pdm_.at(i);
        if (std::isfinite(m)) mass_ += m;
      }
    }
  }
  double mass() const { return mass_; }

 private:
  const Raster<float>& pdm_;
  std::vector<std::uint8_t> seen_;
  double r_;
  double mass_ = 0;
};

}  // namespace

ProbabilityCurves accumulatedProbability(const Raster<float>& pdm,
                                         const std::vector<Trajectory>& trajectories,
                                         double sensingDiameter, std::size_t every) {
  ProbabilityCurves out;
  if (trajectories.empty() || pdm.empty()) return out;
  every = std::max<std::size_t>(every, 1);
  DiscMarker team(pdm, sensingDiameter / 2), single(pdm, sensingDiameter / 2);
  std::size_t end = 0;
  for (const auto& t : trajectories) end = std::max(end, t.samples.size());
  for (std::size_t i = 0; i < end; ++i) {
    double distance = 0;
    for (const auto& t : trajectories) {
      const auto& s = t.samples;
      if (s.empty()) continue;
      const TrajectorySample& x = s[std::min(i, s.size() - 1)];
      distance += x.distance;
      if (i < s.size()) team.mark({x.x, x.y});
    }
    if (i % every == 0 || i + 1 == end)
      out.team.emplace_back(distance / static_cast<double>(trajectories.size()), team.mass());
  }
  const auto& s0 = trajectories[0].samples;
  for (std::size_t i = 0; i < s0.size(); ++i) {
    single.mark({s0[i].x, s0[i].y});
    if (i % every == 0 || i + 1 == s0.size()) out.single.emplace_back(s0[i].distance, single.mass());
  }
  return out;
}

TeamMetrics teamMetrics(const CoordinationResult& plan, const ProbabilityCurves& curves,
                        const Route& route, double attitudeLimit, double safetyDistance) {
  TeamMetrics m;
  double sum = 0;
  for (const auto& t : plan.trajectories) {
    const double len = trajectoryLength(t);
    m.trajectoryM.push_back(len);
    sum += len;
    m.missionTimeS = std::max(m.missionTimeS, t.samples.empty() ? 0.0 : t.samples.back().time);
    const AttitudeExceedance e = attitudeExceedance(t, attitudeLimit);
    m.samples += e.samples;
    m.exceedances += e.count;
    for (const auto& s : t.samples) {
      m.maxRollDeg = std::max(m.maxRollDeg, std::abs(s.roll) * 180.0 / M_PI);
      m.maxPitchDeg = std::max(m.maxPitchDeg, std::abs(s.pitch) * 180.0 / M_PI);
    }
  }
  if (!plan.trajectories.empty()) m.meanTrajectoryM = sum / static_cast<double>(plan.trajectories.size());
  m.exceedanceFraction = m.samples ? static_cast<double>(m.exceedances) / static_cast<double>(m.samples) : 0.0;
  if (!plan.trajectories.empty()) {
    const SeparationReport sep = checkSeparation(plan.trajectories, safetyDistance);
    m.collisions = static_cast<int>(sep.conflicts.size());
    m.minSeparationM = std::isfinite(sep.minimumDistance) ? sep.minimumDistance : 0.0;
  }
  m.accumulatedProbability = curves.team.empty() ? 0.0 : curves.team.back().second;
  m.singleRoverProbability = curves.single.empty() ? 0.0 : curves.single.back().second;
  m.routeScore = route.score;
  m.targets = static_cast<int>(route.cells.size());
  for (const auto& leg : plan.legs) {
    if (leg.target < 0) continue;
    if (leg.status == LegStatus::Reached) ++m.targetsReached;
    if (leg.status == LegStatus::Skipped) ++m.targetsSkipped;
    if (leg.status == LegStatus::Short) ++m.targetsShort;
  }
  m.replans = plan.replans;
  m.waits = plan.waits;
  m.rrtCalls = plan.rrtCalls;
  return m;
}

}  // namespace rover::team
