#include "core/team/sub_teams.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace rover::team {

std::vector<int> subTeamSizes(int n, int size) {
  if (n <= 0) return {};
  if (size <= 0 || size >= n) return {n};
  const int k = (n + size - 1) / size;
  std::vector<int> out(static_cast<std::size_t>(k), n / k);
  for (int i = 0; i < n % k; ++i) ++out[static_cast<std::size_t>(i)];
  return out;
}

SubTeams splitTeam(const std::vector<Pose>& starts, const std::vector<Eigen::Vector2d>& targets,
                   int size) {
  const int n = static_cast<int>(starts.size());
  const std::vector<int> sizes = subTeamSizes(n, size);
  SubTeams out;
  out.ofRover.assign(starts.size(), 0);
  out.ofTarget.assign(targets.size(), 0);
  if (sizes.size() <= 1) {
    out.rovers.emplace_back(static_cast<std::size_t>(n));
    std::iota(out.rovers[0].begin(), out.rovers[0].end(), 0);
    if (n == 0) out.rovers.clear();
    return out;
  }
  const int k = static_cast<int>(sizes.size());
  Eigen::Vector2d centroid(0, 0);
  for (const Pose& s : starts) centroid += Eigen::Vector2d(s.x, s.y);
  centroid /= n;
  // Wedges of neighbouring starts: by angle round the centroid (from east, anticlockwise). The
  // formation's centre rover sits on the centroid; its angle (atan2(0, 0) = 0) puts it first.
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> angle(order.size()), dist(order.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d d = Eigen::Vector2d(starts[i].x, starts[i].y) - centroid;
    dist[i] = d.norm();
    angle[i] = dist[i] < 1e-9 ? 0.0 : std::atan2(d.y(), d.x());
    if (angle[i] < 0) angle[i] += 2 * M_PI;
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (angle[a] != angle[b]) return angle[a] < angle[b];
    return dist[a] < dist[b];
  });
  std::vector<std::vector<int>> groups;
  std::vector<Eigen::Vector2d> groupCentre;
  for (int g = 0, at = 0; g < k; ++g) {
    std::vector<int> members(order.begin() + at, order.begin() + at + sizes[g]);
    at += sizes[g];
    std::sort(members.begin(), members.end());
    Eigen::Vector2d c(0, 0);
    for (int r : members) c += Eigen::Vector2d(starts[r].x, starts[r].y);
    groupCentre.push_back(c / static_cast<double>(members.size()));
    groups.push_back(std::move(members));
  }
  // Contiguous route segments, sizes as equal as possible; with fewer targets than sub-teams the
  // last sub-teams get none (they stay where they are).
  const int t = static_cast<int>(targets.size());
  std::vector<bool> used(groups.size(), false);
  out.rovers.resize(groups.size());
  for (int s = 0, at = 0; s < k; ++s) {
    const int len = t / k + (s < t % k ? 1 : 0);
    // The segment goes to the nearest sub-team not yet given one (ties: the earlier wedge).
    int best = -1;
    double bestD = std::numeric_limits<double>::infinity();
    for (int g = 0; g < k; ++g) {
      if (used[g]) continue;
      const double d = len > 0 ? (groupCentre[g] - targets[at]).norm() : 0.0;
      if (d < bestD) {
        bestD = d;
        best = g;
      }
    }
    used[best] = true;
    out.rovers[s] = groups[best];
    for (int r : groups[best]) out.ofRover[r] = s;
    for (int i = at; i < at + len; ++i) out.ofTarget[i] = s;
    at += len;
  }
  return out;
}

}  // namespace rover::team
