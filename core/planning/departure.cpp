#include "core/planning/departure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>

namespace rover::planning {

namespace {

// The grid the way-out test runs on: every start's surroundings, a border past every disc.
class Window {
 public:
  Window(const std::vector<Eigen::Vector2d>& starts, double safety, const PassableGround& passable)
  {
    Eigen::Vector2d lo = starts.front(), hi = starts.front();
    for (const auto& s : starts) {
      lo = lo.cwiseMin(s);
      hi = hi.cwiseMax(s);
    }
    // An eighth of the safety distance; coarser for starts spread far apart, so the grid stays
    // within about 400 × 400 cells (the test only gets more lenient: the table still keeps the
    // rovers apart).
    // With the ground, ten safety distances farther: getting past the rovers is not getting out
    // of a pocket of passable ground round them (a pocket wider than that is taken as open).
    const double margin = passable ? 10 * safety : 0.0;
    step_ = std::max(safety / 8, ((hi - lo).maxCoeff() + 2 * margin) / 400);
    // The border cells lie farther than the way out keeps (safety + kDepartureMargin) from every
    // start: reaching one is getting past (with the ground, the pocket's margin, as before the
    // departure margin: a map edge 11 safety distances from a start does not shut it in).
    const double grow = std::max(safety + kDepartureMargin, safety + margin) + 2 * step_;
    origin_ = lo - Eigen::Vector2d::Constant(grow);
    cols_ = static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * grow) / step_)) + 1;
    rows_ = static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * grow) / step_)) + 1;
    passable_.assign(static_cast<std::size_t>(rows_) * cols_, 1);
    if (passable)
      for (int r = 0; r < rows_; ++r)
        for (int c = 0; c < cols_; ++c) passable_[index(r, c)] = passable(centre(r, c)) ? 1 : 0;
  }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  double step() const { return step_; }
  std::size_t index(int r, int c) const { return static_cast<std::size_t>(r) * cols_ + c; }
  Eigen::Vector2d centre(int r, int c) const { return origin_ + step_ * Eigen::Vector2d(c, r); }
  bool passable(int r, int c) const { return passable_[index(r, c)] != 0; }
  bool border(int r, int c) const { return r == 0 || c == 0 || r == rows_ - 1 || c == cols_ - 1; }
  // The cell whose centre is nearest `p`.
  std::pair<int, int> cellOf(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d q = (p - origin_) / step_;
    return {static_cast<int>(std::lround(q.y())), static_cast<int>(std::lround(q.x()))};
  }

 private:
  double step_;
  Eigen::Vector2d origin_;
  int rows_ = 0, cols_ = 0;
  std::vector<std::uint8_t> passable_;
};

// Rover `k` gets from its start to the window's border over passable cells whose centres keep
// `keep` (safety + kDepartureMargin) from every other standing start, or, from one of `near` (the
// standing starts nearer k than `keep` plus a grid step), k's own distance to it (at least
// `safety`) less one grid step. `covered` counts, per cell, the standing starts nearer than `keep` (k's own included).
bool hasWayOut(const Window& w, const std::vector<Eigen::Vector2d>& starts, int k, double safety,
               double keep, const std::vector<int>& near, const std::vector<int>& covered) {
  const Eigen::Vector2d me = starts[static_cast<std::size_t>(k)];
  struct Near {
    Eigen::Vector2d at;
    double keep;
  };
  std::vector<Near> nearby;
  for (int j : near) {
    const Eigen::Vector2d s = starts[static_cast<std::size_t>(j)];
    // Its distance, at least the safety distance (a start nearer than that is boxed in: the
    // coordinator refuses it), less a grid step.
    nearby.push_back({s, std::max((s - me).norm(), safety) - w.step()});
  }
  auto free = [&](int r, int c) {
    const Eigen::Vector2d p = w.centre(r, c);
    int within = (p - me).norm() < keep ? 1 : 0;  // covered counts k's own start and the near ones
    for (const Near& n : nearby) {
      const double d = (p - n.at).norm();
      if (d < n.keep) return false;
      if (d < keep) ++within;
    }
    return covered[w.index(r, c)] - within == 0;
  };
  const auto [r0, c0] = w.cellOf(me);
  if (!free(r0, c0)) return false;  // nearer than the safety distance to a standing rover
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(w.rows()) * w.cols(), 0);
  std::deque<std::pair<int, int>> queue{{r0, c0}};
  seen[w.index(r0, c0)] = 1;
  while (!queue.empty()) {
    const auto [r, c] = queue.front();
    queue.pop_front();
    if (w.border(r, c)) return true;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const int nr = r + dr, nc = c + dc;
        const std::size_t i = w.index(nr, nc);
        if (seen[i] || !w.passable(nr, nc) || !free(nr, nc)) continue;
        seen[i] = 1;
        queue.emplace_back(nr, nc);
      }
  }
  return false;
}

}  // namespace

Departure departureOrder(const std::vector<Eigen::Vector2d>& starts, double safety,
                         const PassableGround& passable) {
  Departure out;
  std::vector<int> standing;
  for (int k = 0; k < static_cast<int>(starts.size()); ++k) standing.push_back(k);
  if (starts.empty() || !(safety > 0)) {
    out.order = standing;
    out.firstRound = static_cast<int>(standing.size());
    return out;
  }
  const Window w(starts, safety, passable);
  const double keep = safety + kDepartureMargin;
  const int span = static_cast<int>(std::ceil(keep / w.step()));
  while (!standing.empty()) {
    std::vector<int> covered(static_cast<std::size_t>(w.rows()) * w.cols(), 0);
    for (int j : standing) {
      const Eigen::Vector2d s = starts[static_cast<std::size_t>(j)];
      const auto [rj, cj] = w.cellOf(s);
      for (int r = std::max(0, rj - span); r <= std::min(w.rows() - 1, rj + span); ++r)
        for (int c = std::max(0, cj - span); c <= std::min(w.cols() - 1, cj + span); ++c)
          if ((w.centre(r, c) - s).norm() < keep) ++covered[w.index(r, c)];
    }
    std::vector<int> left, stay;
    for (int k : standing) {
      const Eigen::Vector2d me = starts[static_cast<std::size_t>(k)];
      std::vector<int> near;  // a handful: the starts are pairwise at least `safety` apart
      for (int j : standing)
        if (j != k && (starts[static_cast<std::size_t>(j)] - me).norm() < keep + w.step()) near.push_back(j);
      (hasWayOut(w, starts, k, safety, keep, near, covered) ? left : stay).push_back(k);
    }
    if (left.empty()) {
      out.boxedIn = stay;
      return out;
    }
    if (out.order.empty()) out.firstRound = static_cast<int>(left.size());
    out.order.insert(out.order.end(), left.begin(), left.end());
    standing = std::move(stay);
  }
  return out;
}

}  // namespace rover::planning
