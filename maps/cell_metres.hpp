#pragma once
// The ground size of a raster's cells in metres, from its CRS and geotransform (DESIGN.md: maps/).
// A projected CRS scales by its linear unit; a geographic CRS uses its own ellipsoid (meridional
// radius of curvature M(φ) north-south, N(φ)·cos φ east-west per row); an equidistant cylindrical
// projection (global PDS/ISIS products) shrinks each row's width by cos φ / cos φts.
#include <array>
#include <vector>

#include <ogr_srs_api.h>

namespace rover::maps {

struct CellMetres {
  double dx = 0, dy = 0;             // at the grid's centre row
  std::vector<double> rowCellWidth;  // per row, north first; empty when every row is dx wide
};

// `srs` may be null (no CRS: the geotransform's units are taken as metres).
CellMetres cellMetres(OGRSpatialReferenceH srs, const std::array<double, 6>& gt, int rows);

}  // namespace rover::maps
