#pragma once
// Local frame (SPEC §0: metres east/north of the raster's lower-left corner) <-> the map's own CRS,
// through the GDAL geotransform. The local frame is the pixel grid scaled by the nominal cell size
// (GridGeometry::cellWidth/cellHeight), so the mapping is exact for every raster GDAL describes.
#include <Eigen/Core>

#include <string>

#include "core/grid/raster.hpp"
#include "core/terrain/body.hpp"

namespace rover::maps {

Eigen::Vector2d localToCrs(const GridGeometry& g, const GeoReference& geo, const Eigen::Vector2d& xy);
Eigen::Vector2d crsToLocal(const GridGeometry& g, const GeoReference& geo, const Eigen::Vector2d& XY);

// The body a CRS lies on, from its ellipsoid and datum names and its semi-major axis
// (terrain::detectBody); Unknown for an empty or unreadable WKT or an unrecognised ellipsoid.
terrain::Body bodyOfCrs(const std::string& crsWkt);

}  // namespace rover::maps
