#pragma once
// A mission's trajectories as CSV (issue 13: exports a GIS user can use): one row per sample of
// each rover, in the local frame and in the map's CRS. Columns (README "Exports"):
//   rover, then time_s (a planner with a clock: team, every 10 Hz sample) or move (coverage: the
//   point after that many of the rover's moves, 0 = the start), x_m, y_m (local frame), the CRS
//   pair (easting_m, northing_m for a projected CRS in metres; lon_deg, lat_deg for a geographic
//   one; crs_x, crs_y when the CRS is unknown or in other units), heading_deg (counter-clockwise
//   from east), roll_deg, pitch_deg, speed_m_s (team only), elevation_m, and under localisation
//   error believed_x_m, believed_y_m. Empty cells where the value is unknown (off the DEM).
#include <string>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/planning/plan_result.hpp"
#include "core/terrain/dem.hpp"

namespace rover::maps {

// The names of the CRS's two coordinate columns (see above).
std::pair<std::string, std::string> crsColumnNames(const GeoReference& geo);

// `startHeadings` (radians, one per rover; missing ones count as 0) and `dem` (may be null) give
// a coverage rover's heading, attitude and height (core/planning/ground_sample.hpp); `demOrigin`
// is where the DEM's lower-left corner lies in `g`'s frame (a mission area's planning window).
std::string resultCsv(const std::vector<Track>& tracks, const GridGeometry& g, const GeoReference& geo,
                      const terrain::Dem* dem, const std::vector<double>& startHeadings,
                      const Eigen::Vector2d& demOrigin = Eigen::Vector2d::Zero());

}  // namespace rover::maps
