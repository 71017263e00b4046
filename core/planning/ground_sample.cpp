#include "core/planning/ground_sample.hpp"

#include <cmath>

#include "core/terrain/layers.hpp"

namespace rover {

TrackSample groundSample(const std::vector<Eigen::Vector2d>& points, std::size_t i,
                         double startHeading, const terrain::Dem* dem) {
  TrackSample s;
  s.position = points[i];
  s.heading = startHeading;
  // The last move that went somewhere (a wait repeats the point and keeps the heading).
  for (std::size_t j = i; j > 0; --j) {
    const Eigen::Vector2d d = points[j] - points[j - 1];
    if (d.squaredNorm() > 0) {
      s.heading = std::atan2(d.y(), d.x());
      break;
    }
  }
  if (dem == nullptr) return s;
  if (auto p = terrain::surfaceAt(*dem, s.position.x(), s.position.y())) s.elevation = p->height;
  if (auto a = terrain::attitudeAt(*dem, s.position.x(), s.position.y(), s.heading)) {
    s.roll = a->roll;
    s.pitch = a->pitch;
  }
  return s;
}

}  // namespace rover
