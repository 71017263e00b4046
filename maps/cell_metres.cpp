#include "maps/cell_metres.hpp"

#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace rover::maps {

CellMetres cellMetres(OGRSpatialReferenceH srs, const std::array<double, 6>& gt, int rows) {
  CellMetres out;
  double dx = std::fabs(gt[1]), dy = std::fabs(gt[5]);
  if (srs && OSRIsGeographic(srs)) {
    // Geographic CRS: metres from the CRS's own ellipsoid — the meridional radius of curvature
    // M(φ) north-south and N(φ)·cos φ east-west, per row.
    OGRErr e = OGRERR_NONE;
    double a = OSRGetSemiMajor(srs, &e), b = OSRGetSemiMinor(srs, &e);
    double e2 = 1.0 - (b * b) / (a * a), unit = OSRGetAngularUnits(srs, nullptr);
    auto latOf = [&](double row) { return (gt[3] + row * gt[5]) * unit; };
    auto M = [&](double phi) {
      double s = std::sin(phi);
      return a * (1 - e2) / std::pow(1 - e2 * s * s, 1.5);
    };
    auto N = [&](double phi) {
      double s = std::sin(phi);
      return a / std::sqrt(1 - e2 * s * s);
    };
    out.rowCellWidth.resize(rows);
    for (int r = 0; r < rows; ++r) {
      double phi = latOf(r + 0.5);
      out.rowCellWidth[r] = std::max(1e-6, N(phi) * std::cos(phi) * std::fabs(gt[1]) * unit);
    }
    double phiC = latOf(rows / 2.0);
    dy = M(phiC) * std::fabs(gt[5]) * unit;
    dx = std::max(1e-6, N(phiC) * std::cos(phiC) * std::fabs(gt[1]) * unit);
  } else if (srs) {
    double lu = OSRGetLinearUnits(srs, nullptr);
    dx *= lu;
    dy *= lu;
    const char* proj = OSRGetAttrValue(srs, "PROJECTION", 0);
    if (proj && std::string(proj) == SRS_PT_EQUIRECTANGULAR) {
      // Equidistant cylindrical (global PDS/ISIS products): x = R(λ−λ0)·cos φts, y = R(φ−φ0), so
      // one pixel spans dx·cos φ / cos φts on the ground. Without this, slopes towards the poles
      // of a global map come out far too gentle.
      OGRErr e = OGRERR_NONE;
      const double R = OSRGetSemiMajor(srs, &e);
      const double deg = std::numbers::pi / 180.0;
      const double phiTs = OSRGetProjParm(srs, SRS_PP_STANDARD_PARALLEL_1, 0.0, &e) * deg;
      const double phi0 = OSRGetProjParm(srs, SRS_PP_LATITUDE_OF_ORIGIN, 0.0, &e) * deg;
      const double fn = OSRGetProjParm(srs, SRS_PP_FALSE_NORTHING, 0.0, &e);
      out.rowCellWidth.resize(rows);
      for (int r = 0; r < rows; ++r) {
        double phi = ((gt[3] + (r + 0.5) * gt[5]) * lu - fn) / R + phi0;
        out.rowCellWidth[r] = std::max(1e-6, dx * std::cos(phi) / std::cos(phiTs));
      }
      double phiC = ((gt[3] + rows / 2.0 * gt[5]) * lu - fn) / R + phi0;
      dx = std::max(1e-6, dx * std::cos(phiC) / std::cos(phiTs));
    }
  }
  out.dx = dx;
  out.dy = dy;
  return out;
}

}  // namespace rover::maps
