#include "core/team/separation.hpp"

#include <algorithm>
#include <limits>

#include "core/common/error.hpp"

namespace rover::team {

Eigen::Vector2d positionAtIndex(const Trajectory& t, std::size_t i) {
  const TrajectorySample& s = t.samples[std::min(i, t.samples.size() - 1)];
  return {s.x, s.y};
}

std::optional<Conflict> conflictAt(std::span<const Trajectory> others, int rover, std::size_t index,
                                   const Eigen::Vector2d& p, double safety, double period) {
  for (std::size_t j = 0; j < others.size(); ++j) {
    const Eigen::Vector2d o = positionAtIndex(others[j], index);
    const double d = (p - o).norm();
    if (d < safety)
      return Conflict{rover, static_cast<int>(j), static_cast<double>(index) * period, 0.0, d, p, o};
  }
  return std::nullopt;
}

SeparationReport checkSeparation(const std::vector<Trajectory>& trajectories, double safety) {
  SeparationReport r;
  r.minimumDistance = std::numeric_limits<double>::infinity();
  std::size_t end = 0;
  for (const auto& t : trajectories) {
    if (t.samples.empty()) throw Error(ErrorCode::InvalidInput, "trajectory", "a trajectory has no samples");
    end = std::max(end, t.samples.size());
  }
  const double period = trajectories.empty() ? 0.1 : trajectories.front().samplePeriod;
  for (std::size_t a = 0; a < trajectories.size(); ++a) {
    for (std::size_t b = a + 1; b < trajectories.size(); ++b) {
      std::optional<Conflict> open;
      for (std::size_t i = 0; i < end; ++i) {
        const Eigen::Vector2d pa = positionAtIndex(trajectories[a], i);
        const Eigen::Vector2d pb = positionAtIndex(trajectories[b], i);
        const double d = (pa - pb).norm();
        if (d < r.minimumDistance) {
          r.minimumDistance = d;
          r.minimumTime = static_cast<double>(i) * period;
          r.minimumPair[0] = static_cast<int>(a);
          r.minimumPair[1] = static_cast<int>(b);
        }
        if (d < safety) {
          if (!open) open = Conflict{static_cast<int>(b), static_cast<int>(a),
                                     static_cast<double>(i) * period, 0.0, d, pb, pa};
          open->distance = std::min(open->distance, d);
          open->duration = static_cast<double>(i) * period - open->time;
        } else if (open) {
          r.conflicts.push_back(*open);
          open.reset();
        }
      }
      if (open) r.conflicts.push_back(*open);
    }
  }
  std::sort(r.conflicts.begin(), r.conflicts.end(),
            [](const Conflict& x, const Conflict& y) { return x.time < y.time; });
  return r;
}

}  // namespace rover::team
