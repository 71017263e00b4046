#include "maps/georef.hpp"

#include <ogr_srs_api.h>

#include <array>
#include <cmath>

#include "core/common/error.hpp"

namespace rover::maps {

namespace {

// The geotransform that maps pixels to CRS coordinates. Without a georeference the CRS is the local
// frame itself: origin at the top-left corner, y north, so localToCrs is the identity.
std::array<double, 6> effectiveGeotransform(const GridGeometry& g, const GeoReference& geo) {
  if (geo.valid) return geo.geotransform;
  return {0.0, g.cellWidth, 0.0, g.rows * g.cellHeight, 0.0, -g.cellHeight};
}

}  // namespace

Eigen::Vector2d localToCrs(const GridGeometry& g, const GeoReference& geo,
                           const Eigen::Vector2d& xy) {
  const auto gt = effectiveGeotransform(g, geo);
  // Pixel coordinates (GDAL convention: (0, 0) is the top-left corner of the top-left pixel).
  const double col = xy.x() / g.cellWidth;
  const double row = g.rows - xy.y() / g.cellHeight;
  return {gt[0] + col * gt[1] + row * gt[2], gt[3] + col * gt[4] + row * gt[5]};
}

Eigen::Vector2d crsToLocal(const GridGeometry& g, const GeoReference& geo,
                           const Eigen::Vector2d& XY) {
  const auto gt = effectiveGeotransform(g, geo);
  // Invert the 2×2 linear part [gt1 gt2; gt4 gt5] (rotated/sheared geotransforms included).
  const double det = gt[1] * gt[5] - gt[2] * gt[4];
  if (det == 0.0 || !std::isfinite(det))
    throw Error(ErrorCode::InvalidInput, "geotransform",
                "the geotransform is singular; CRS coordinates cannot be converted to the grid");
  const double dX = XY.x() - gt[0];
  const double dY = XY.y() - gt[3];
  const double col = (gt[5] * dX - gt[2] * dY) / det;
  const double row = (-gt[4] * dX + gt[1] * dY) / det;
  return {col * g.cellWidth, (g.rows - row) * g.cellHeight};
}

terrain::Body bodyOfCrs(const std::string& crsWkt) {
  if (crsWkt.empty()) return terrain::Body::Unknown;
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  terrain::Body body = terrain::Body::Unknown;
  std::string text = crsWkt;  // OSRImportFromWkt advances a char* through its argument
  char* cursor = text.data();
  if (OSRImportFromWkt(srs, &cursor) == OGRERR_NONE) {
    OGRErr err = OGRERR_NONE;
    const double a = OSRGetSemiMajor(srs, &err);
    const char* ellipsoid = OSRGetAttrValue(srs, "SPHEROID", 0);
    if (!ellipsoid) ellipsoid = OSRGetAttrValue(srs, "ELLIPSOID", 0);
    const char* datum = OSRGetAttrValue(srs, "DATUM", 0);
    body = terrain::detectBody(ellipsoid ? ellipsoid : "", datum ? datum : "",
                               err == OGRERR_NONE ? a : 0.0);
  }
  OSRDestroySpatialReference(srs);
  return body;
}

}  // namespace rover::maps
