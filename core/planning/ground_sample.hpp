#pragma once
// A rover's state at one point of a path whose steps are grid moves (coverage), for the exports:
// heading = the direction of the move that arrived there (the start heading at the first point),
// roll and pitch = the ground's attitude under a rover standing there with that heading, height =
// the DEM's (terrain::surfaceAt / attitudeAt, SPEC §2). No clock and no speed: those stay NaN.
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/planning/plan_result.hpp"
#include "core/terrain/dem.hpp"

namespace rover {

// `dem` may be null (then only position and heading are set); points outside the DEM or next to
// nodata keep NaN attitude and height.
TrackSample groundSample(const std::vector<Eigen::Vector2d>& points, std::size_t i,
                         double startHeading, const terrain::Dem* dem);

}  // namespace rover
