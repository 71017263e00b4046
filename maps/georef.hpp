#pragma once
// Local frame (SPEC §0: metres east/north of the raster's lower-left corner) <-> the map's own CRS,
// through the GDAL geotransform. The local frame is the pixel grid scaled by the nominal cell size
// (GridGeometry::cellWidth/cellHeight), so the mapping is exact for every raster GDAL describes.
#include <Eigen/Core>
#include <ogr_srs_api.h>

#include <array>
#include <optional>
#include <string>

#include "core/grid/raster.hpp"
#include "core/terrain/body.hpp"

namespace rover::maps {

Eigen::Vector2d localToCrs(const GridGeometry& g, const GeoReference& geo, const Eigen::Vector2d& xy);
Eigen::Vector2d crsToLocal(const GridGeometry& g, const GeoReference& geo, const Eigen::Vector2d& XY);

// The body a CRS lies on, from its ellipsoid and datum names and its semi-major axis
// (terrain::detectBody); Unknown for an empty or unreadable WKT or an unrecognised ellipsoid.
terrain::Body bodyOfCrs(const std::string& crsWkt);

// --- Georeferencing checked at import (issue 22) ---------------------------------------------
// A file's geotransform is the client's word: a NaN, zero, 1e-300 or 1e300 pixel size, or a
// latitude of 95°, would become a map whose cell size is not a number and crash a planner. Every
// raster read (uploads, PDM rasters, the CLI's files) is checked against these bounds first.
//
// Pixel sizes, in metres on the ground: [1 mm, 100 km]. The same range as the `cell` import
// option: 1 mm is below any DEM product (HiRISE DTMs are 1 m, rover-scale site models ~1 cm), and
// 100 km covers the coarsest global grids (the Moon at 1 px/deg is 30 km, Mars 59 km). A geographic
// CRS's pixel, in degrees, is converted with the CRS's own semi-major axis (one degree of arc on the
// equator), so the range in degrees is that body's: about [1.7e-8°, 1.7°] on Mars, [3.3e-8°, 3.3°]
// on the Moon, [9e-9°, 0.9°] on Earth.
constexpr double kMinPixelMetres = 1e-3;
constexpr double kMaxPixelMetres = 1e5;
// Projected coordinates (origin and extent), in metres: |X|, |Y| <= 1e8 m (100 000 km; the
// Earth's equator is 40 075 km, so every real projection of Earth, Mars or the Moon fits).
constexpr double kMaxProjectedMetres = 1e8;
// Geographic coordinates, in degrees: latitude in [-90, 90], longitude in [-360, 360] (a map
// may run 0..360 or -180..180, never further), each edge allowed one pixel beyond them (grids
// registered on pixel centres put their outer edges half a pixel past the pole).

// What a CRS's units are worth, for checking a geotransform.
struct CrsUnits {
  bool geographic = false;
  double degreesPerUnit = 1.0;  // geographic: one CRS unit in degrees
  double metresPerUnit = 1.0;   // projected: the linear unit; geographic: one unit of arc on the equator
};
// Units of a CRS (null: none, metres assumed) / of its WKT ("" or unreadable: metres).
CrsUnits crsUnits(OGRSpatialReferenceH srs);
CrsUnits crsUnitsOfWkt(const std::string& wkt);

// A geotransform's first problem: `field` is "geotransform.<part>" (origin_x, pixel_width,
// row_rotation, origin_y, column_rotation, pixel_height, or "geotransform" for a singular one)
// and `reason` says what is wrong in words, with the value. Rotated and sheared geotransforms are
// checked by the lengths of their pixel's sides and the positions of the four corners.
struct GeorefProblem {
  std::string field, reason;
};
std::optional<GeorefProblem> georefProblem(const std::array<double, 6>& gt, int rows, int cols, const CrsUnits& units);
// Throws rover::Error (InvalidInput, the problem's field) for the first problem, if any.
void checkGeoreference(const GeoReference& geo, int rows, int cols);

}  // namespace rover::maps
