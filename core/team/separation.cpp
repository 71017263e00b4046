#include "core/team/separation.hpp"

#include <algorithm>
#include <limits>

#include "core/common/error.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::team {

Eigen::Vector2d positionAtIndex(const Trajectory& t, std::size_t i) {
  const TrajectorySample& s = t.samples[std::min(i, t.samples.size() - 1)];
  return {s.x, s.y};
}

void TrafficTable::add(const Trajectory& t) {
  if (t.samples.empty()) throw Error(ErrorCode::InvalidInput, "trajectory", "a trajectory has no samples");
  planning::checkRoverCount(rovers_.size() + 1);  // the one being added
  rovers_.emplace_back();
  replace(static_cast<int>(rovers_.size()) - 1, t);
}

void TrafficTable::replace(int rover, const Trajectory& t) {
  if (t.samples.empty()) throw Error(ErrorCode::InvalidInput, "trajectory", "a trajectory has no samples");
  Track track;
  track.at.reserve(t.samples.size());
  for (const auto& s : t.samples) track.at.emplace_back(s.x, s.y);
  for (std::size_t b = 0; b * kBlock < track.at.size(); ++b) {
    const std::size_t last = std::min(track.at.size(), (b + 1) * kBlock);
    Box box = Box::of(track.at[b * kBlock]);
    for (std::size_t i = b * kBlock + 1; i < last; ++i) box.extend(track.at[i]);
    track.boxes.push_back(box);
  }
  rovers_.at(static_cast<std::size_t>(rover)) = std::move(track);
  end_ = 0;
  for (const Track& r : rovers_) end_ = std::max(end_, r.at.size());
}

// A block past a rover's last sample holds its parked position (and so does the rest of its last
// block, inside that block's box).
TrafficTable::Box TrafficTable::boxAt(const Track& t, std::size_t block) const {
  if (block < t.boxes.size()) return t.boxes[block];
  return Box::of(t.at.back());
}

template <class Pos>
std::optional<Conflict> TrafficTable::scanBlock(int rover, std::size_t from, std::size_t count,
                                                const Box& box, const Pos& pos) const {
  // Rovers whose block box comes within the safety distance of the rover's box (plus a micrometre,
  // so rounding can never skip a pair the exact check would catch).
  const double reach = safety_ + 1e-6;
  const std::size_t block = from / kBlock;
  int nearList[kMaxRovers];
  int nearCount = 0;
  for (std::size_t j = 0; j < rovers_.size(); ++j) {
    if (static_cast<int>(j) == rover) continue;
    const Box o = boxAt(rovers_[j], block);
    const double dx = std::max({0.0, box.x0 - o.x1, o.x0 - box.x1});
    const double dy = std::max({0.0, box.y0 - o.y1, o.y0 - box.y1});
    if (dx * dx + dy * dy >= reach * reach) continue;
    nearList[nearCount++] = static_cast<int>(j);
  }
  if (nearCount == 0) return std::nullopt;
  for (std::size_t m = 0; m < count; ++m) {
    const std::size_t index = from + m;
    const Eigen::Vector2d p = pos(m);
    for (int n = 0; n < nearCount; ++n) {
      const Track& t = rovers_[static_cast<std::size_t>(nearList[n])];
      const Eigen::Vector2d& o = t.at[std::min(index, t.at.size() - 1)];
      const double d = (p - o).norm();
      if (d < safety_)
        return Conflict{rover, nearList[n], static_cast<double>(index) * period_, index, 0.0, d, p, o};
    }
  }
  return std::nullopt;
}

std::optional<Conflict> TrafficTable::standing(int rover, const Eigen::Vector2d& p,
                                               std::size_t from, std::size_t to) const {
  if (from >= to) return std::nullopt;
  // Past every rover's end nothing moves: one index stands for the rest.
  if (to > end_) to = std::max(from, end_) + 1;
  const Box box = Box::of(p);
  for (std::size_t i = from; i < to;) {
    const std::size_t count = std::min(to, (i / kBlock + 1) * kBlock) - i;
    if (auto c = scanBlock(rover, i, count, box, [&](std::size_t) { return p; })) return c;
    i += count;
  }
  return std::nullopt;
}

std::optional<Conflict> TrafficTable::driving(int rover, std::span<const TrajectorySample> samples,
                                              std::size_t from) const {
  for (std::size_t m = 0; m < samples.size();) {
    const std::size_t i = from + m;
    const std::size_t count = std::min(samples.size() - m, (i / kBlock + 1) * kBlock - i);
    Box box = Box::of({samples[m].x, samples[m].y});
    for (std::size_t q = m + 1; q < m + count; ++q) box.extend({samples[q].x, samples[q].y});
    const std::size_t base = m;
    if (auto c = scanBlock(rover, i, count, box, [&](std::size_t q) {
          return Eigen::Vector2d(samples[base + q].x, samples[base + q].y);
        }))
      return c;
    m += count;
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
                                     static_cast<double>(i) * period, i, 0.0, d, pb, pa};
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
