#include "maps/georef.hpp"

#include <ogr_srs_api.h>

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

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

namespace {

std::string num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

constexpr const char* kParts[6] = {"origin_x", "pixel_width", "row_rotation", "origin_y", "column_rotation", "pixel_height"};

std::string part(int i) { return std::string("geotransform.") + kParts[i]; }

}  // namespace

CrsUnits crsUnits(OGRSpatialReferenceH srs) {
  CrsUnits u;
  if (!srs) return u;
  if (OSRIsGeographic(srs)) {
    u.geographic = true;
    const double radians = OSRGetAngularUnits(srs, nullptr);
    OGRErr err = OGRERR_NONE;
    const double a = OSRGetSemiMajor(srs, &err);
    u.degreesPerUnit = radians * 180.0 / std::numbers::pi;
    u.metresPerUnit = radians * (err == OGRERR_NONE && a > 0 ? a : 6378137.0);
  } else {
    const double m = OSRGetLinearUnits(srs, nullptr);
    u.metresPerUnit = m > 0 && std::isfinite(m) ? m : 1.0;
  }
  if (!(u.degreesPerUnit > 0) || !std::isfinite(u.degreesPerUnit)) u.degreesPerUnit = 1.0;
  if (!(u.metresPerUnit > 0) || !std::isfinite(u.metresPerUnit)) u.metresPerUnit = 1.0;
  return u;
}

CrsUnits crsUnitsOfWkt(const std::string& wkt) {
  if (wkt.empty()) return {};
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  std::string text = wkt;
  char* cursor = text.data();
  const CrsUnits u = OSRImportFromWkt(srs, &cursor) == OGRERR_NONE ? crsUnits(srs) : CrsUnits{};
  OSRDestroySpatialReference(srs);
  return u;
}

std::optional<GeorefProblem> georefProblem(const std::array<double, 6>& gt, int rows, int cols, const CrsUnits& u) {
  // Pixel sizes first: a GeoTIFF stores a tie point and a pixel scale, so a NaN scale makes the
  // origin GDAL derives NaN too, and the scale is the one to name.
  for (int i : {1, 5, 2, 4, 0, 3})
    if (!std::isfinite(gt[i])) return GeorefProblem{part(i), "the geotransform's " + std::string(kParts[i]) + " is " + num(gt[i]) + ", not a finite number"};
  // The sides of one pixel, in CRS units then metres (a rotated pixel's sides are its columns'
  // and rows' steps).
  const double side[2] = {std::hypot(gt[1], gt[4]), std::hypot(gt[2], gt[5])};
  const int sidePart[2] = {1, 5};
  for (int k = 0; k < 2; ++k) {
    const double metres = side[k] * u.metresPerUnit;
    const std::string what = k == 0 ? "pixel width" : "pixel height";
    const std::string shown = u.geographic ? num(side[k] * u.degreesPerUnit) + "° (" + num(metres) + " m on this body)"
                                           : num(metres) + " m";
    if (side[k] == 0) return GeorefProblem{part(sidePart[k]), "the " + what + " is zero"};
    if (!(metres >= kMinPixelMetres && metres <= kMaxPixelMetres))
      return GeorefProblem{part(sidePart[k]), "the " + what + " of " + shown + " is outside the accepted range of " +
                                                  num(kMinPixelMetres) + " to " + num(kMaxPixelMetres) + " m"};
  }
  const double det = gt[1] * gt[5] - gt[2] * gt[4];
  if (!std::isfinite(det) || std::fabs(det) < 1e-12 * side[0] * side[1])
    return GeorefProblem{"geotransform", "the geotransform is singular: its pixels have no area"};
  // The four corners. A corner past the bounds blames the origin when the origin itself is past
  // them, else the pixel size that carried the raster there.
  const double corner[4][2] = {{0, 0}, {static_cast<double>(cols), 0}, {0, static_cast<double>(rows)},
                               {static_cast<double>(cols), static_cast<double>(rows)}};
  for (int axis = 0; axis < 2; ++axis) {  // 0: X (east / longitude), 1: Y (north / latitude)
    const int origin = axis == 0 ? 0 : 3;
    const double scale = u.geographic ? u.degreesPerUnit : u.metresPerUnit;
    double limit = u.geographic ? (axis == 0 ? 360.0 : 90.0) : kMaxProjectedMetres;
    if (u.geographic) limit += side[axis] * u.degreesPerUnit;  // one pixel of slack (see georef.hpp)
    const std::string name = u.geographic ? (axis == 0 ? "longitude" : "latitude") : (axis == 0 ? "X" : "Y");
    const std::string unit = u.geographic ? "°" : " m";
    for (const auto& c : corner) {
      const double v = (axis == 0 ? gt[0] + c[0] * gt[1] + c[1] * gt[2] : gt[3] + c[0] * gt[4] + c[1] * gt[5]) * scale;
      if (std::isfinite(v) && std::fabs(v) <= limit) continue;
      const bool atOrigin = c[0] == 0 && c[1] == 0;
      const std::string bound = u.geographic ? (axis == 0 ? "[-360, 360]°" : "[-90, 90]°") : "±" + num(kMaxProjectedMetres) + " m";
      return GeorefProblem{atOrigin ? part(origin) : part(sidePart[axis]),
                           atOrigin ? "the origin's " + name + " of " + num(v) + unit + " is outside " + bound
                                    : "the raster reaches a " + name + " of " + num(v) + unit + " (" + std::to_string(rows) +
                                          " x " + std::to_string(cols) + " pixels from the origin), outside " + bound};
    }
  }
  return std::nullopt;
}

void checkGeoreference(const GeoReference& geo, int rows, int cols) {
  if (!geo.valid) return;
  if (auto p = georefProblem(geo.geotransform, rows, cols, crsUnitsOfWkt(geo.crsWkt)))
    throw Error(ErrorCode::InvalidInput, p->field, p->reason);
}

}  // namespace rover::maps
