#pragma once
// A DEM's identity for mission files (issue 13): the SHA-256 of what a planner sees of it, not of
// the file it came in. Two uploads of the same raster (same crop and cell) have the same digest
// whatever their container (GeoTIFF, PDS3, a zip), so a mission file names its ground exactly.
#include <string>

#include "core/terrain/dem.hpp"

namespace rover::maps {

// Lower-case hex SHA-256 of: "roverplan-dem-v1", rows and cols (int64 little-endian), the cell
// width and height (float64), the per-row cell widths when the map has them, then every height
// as float32 row by row from the top (NaN written as one canonical quiet NaN).
std::string demSha256(const terrain::Dem& dem);

}  // namespace rover::maps
