#pragma once
// An exact nearest-neighbour structure for RRT* on the plane: elements bucketed on a uniform grid
// over the search bounds, queried by the cells a query's radius touches. OMPL's default for
// RRTstar is GNAT, built for any metric space; in R² with a bounded box a grid answers the same
// queries with far fewer distance calls (GNAT and its distance calls were about 15 % of a team
// mission's profile, issue 10). Answers are GNAT's: every element within the radius (inclusive),
// sorted by distance from the query. Each bucket keeps its elements' positions, and distances are
// planeDistance of two positions: the number RRTstar's distance function gives in R², bit for
// bit, without the calls through that function, the state space and the states (they were 10 %
// of a mission's profile). So the function OMPL sets (setDistanceFunction) is never called: this
// structure is for RealVectorStateSpace(2) only. Exact ties (duplicate states) come in storage
// order here and in GNAT's own storage order there; RRT* plans were identical on every mission
// compared. Queries reuse scratch buffers: one structure serves one planner, never concurrent
// queries.
#include <ompl/datastructures/NearestNeighbors.h>
#include <ompl/util/Exception.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

namespace rover::team {

// OMPL's RealVectorStateSpace::distance in two dimensions, operation for operation:
// sqrt((0 + d0²) + d1²) with d = a − b (a test checks the two agree bit for bit).
inline double planeDistance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const double d0 = a.x() - b.x(), d1 = a.y() - b.y();
  double sum = 0.0;
  sum += d0 * d0;
  sum += d1 * d1;
  return std::sqrt(sum);
}

template <class T>
class GridNearestNeighbors : public ompl::NearestNeighbors<T> {
 public:
  using Position = std::function<Eigen::Vector2d(const T&)>;
  // `min`, `max`: the box every element lies in (positions outside are clamped to its edge
  // cells, still exact); `cell`: the side of a bucket, m.
  GridNearestNeighbors(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell,
                       Position position)
      : min_(min), cell_(cell), position_(std::move(position)) {
    cols_ = std::max(1, static_cast<int>(std::ceil((max.x() - min.x()) / cell)));
    rows_ = std::max(1, static_cast<int>(std::ceil((max.y() - min.y()) / cell)));
    buckets_.resize(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_));
  }

  bool reportsSortedResults() const override { return true; }
  void clear() override {
    for (auto& b : buckets_) b.clear();
    size_ = 0;
  }
  void add(const T& data) override {
    const Eigen::Vector2d p = position_(data);
    buckets_[bucketOf(p)].push_back({p, data});
    ++size_;
  }
  bool remove(const T& data) override {
    auto& b = buckets_[bucketOf(position_(data))];
    auto it = std::find_if(b.begin(), b.end(), [&](const Entry& e) { return e.data == data; });
    if (it == b.end()) return false;
    b.erase(it);
    --size_;
    return true;
  }
  T nearest(const T& data) const override {
    nearestK(data, 1, one_);
    if (one_.empty())
      throw ompl::Exception("No elements found in nearest neighbors data structure");
    return one_.front();
  }
  // Rings of buckets around the query's, until the k-th best is closer than any unvisited bucket.
  void nearestK(const T& data, std::size_t k, std::vector<T>& nbh) const override {
    nbh.clear();
    if (k == 0 || size_ == 0) return;
    const Eigen::Vector2d q = position_(data);
    const auto [qc, qr] = cellOf(q);
    auto& best = found_;
    best.clear();
    const int rings = std::max(cols_, rows_);
    auto visit = [&](int r, int c) {
      if (r < 0 || c < 0 || r >= rows_ || c >= cols_) return;
      for (const Entry& e : buckets_[static_cast<std::size_t>(r) * cols_ + c])
        best.emplace_back(planeDistance(q, e.position), &e.data);
    };
    for (int ring = 0; ring <= rings; ++ring) {
      if (ring == 0) {
        visit(qr, qc);
      } else {  // the ring's four sides only: O(ring) buckets, not its whole square
        for (int c = qc - ring; c <= qc + ring; ++c) {
          visit(qr - ring, c);
          visit(qr + ring, c);
        }
        for (int r = qr - ring + 1; r <= qr + ring - 1; ++r) {
          visit(r, qc - ring);
          visit(r, qc + ring);
        }
      }
      if (best.size() >= k) {
        std::partial_sort(best.begin(), best.begin() + static_cast<std::ptrdiff_t>(k), best.end());
        best.resize(k);
        // Every element of a bucket `ring + 1` or more rings out is at least ring × cell away.
        if (best.back().first <= ring * cell_) break;
      }
    }
    std::sort(best.begin(), best.end());
    if (best.size() > k) best.resize(k);
    for (const auto& b : best) nbh.push_back(*b.second);
  }
  void nearestR(const T& data, double radius, std::vector<T>& nbh) const override {
    nbh.clear();
    const Eigen::Vector2d p = position_(data);
    const auto [c0, r0] = cellOf(p - Eigen::Vector2d::Constant(radius));
    const auto [c1, r1] = cellOf(p + Eigen::Vector2d::Constant(radius));
    auto& found = found_;
    found.clear();
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c)
        for (const Entry& e : buckets_[static_cast<std::size_t>(r) * cols_ + c]) {
          const double d = planeDistance(p, e.position);
          if (d <= radius) found.emplace_back(d, &e.data);
        }
    std::sort(found.begin(), found.end());
    nbh.reserve(found.size());
    for (const auto& f : found) nbh.push_back(*f.second);
  }
  std::size_t size() const override { return size_; }
  void list(std::vector<T>& data) const override {
    data.clear();
    data.reserve(size_);
    for (const auto& b : buckets_)
      for (const Entry& e : b) data.push_back(e.data);
  }

 private:
  struct Entry {
    Eigen::Vector2d position;
    T data;
  };
  std::pair<int, int> cellOf(const Eigen::Vector2d& p) const {
    const double fc = std::floor((p.x() - min_.x()) / cell_), fr = std::floor((p.y() - min_.y()) / cell_);
    // Clamped into the grid (±∞ to its edges); NaN to the first bucket.
    const int c = std::isnan(fc) ? 0 : static_cast<int>(std::clamp(fc, 0.0, cols_ - 1.0));
    const int r = std::isnan(fr) ? 0 : static_cast<int>(std::clamp(fr, 0.0, rows_ - 1.0));
    return {c, r};
  }
  std::size_t bucketOf(const Eigen::Vector2d& p) const {
    const auto [c, r] = cellOf(p);
    return static_cast<std::size_t>(r) * cols_ + c;
  }
  Eigen::Vector2d min_;
  double cell_;
  Position position_;
  int cols_ = 1, rows_ = 1;
  std::vector<std::vector<Entry>> buckets_;
  std::size_t size_ = 0;
  mutable std::vector<std::pair<double, const T*>> found_;  // scratch of the queries
  mutable std::vector<T> one_;                               // nearest()'s answer
};

}  // namespace rover::team
