#pragma once
// The light of terrain::hillshade (gdaldem hillshade) on one cell of Horn's gradient (x, y) (see
// terrain::hornRow): shared by the hillshade raster and the renderer that shades elevation tiles
// straight from Horn's sums (maps/render.cpp), so both give the same number for every cell.
#include <cmath>
#include <numbers>

namespace rover::terrain {

class HillshadeLight {
 public:
  // Azimuth clockwise from north, altitude above the horizon, both in degrees.
  explicit HillshadeLight(double azimuthDeg = 315.0, double altitudeDeg = 45.0, double zFactor = 1.0) {
    constexpr double kRadToDeg = 180.0 / std::numbers::pi;
    const double az = azimuthDeg / kRadToDeg, alt = altitudeDeg / kRadToDeg;
    sinAlt_ = std::sin(alt);
    zCosAlt_ = zFactor * std::cos(alt);
    cosAz_ = std::cos(az);
    sinAz_ = std::sin(az);
    z2_ = zFactor * zFactor;
  }
  // The shade 1..255 (before the raster rounds it to float).
  double operator()(double x, double y) const {
    // gdaldem: cang = (sin alt − z·cos alt·(y·cos az − x·sin az)) / sqrt(1 + z²(x² + y²)).
    const double cang = (sinAlt_ - zCosAlt_ * (y * cosAz_ - x * sinAz_)) / std::sqrt(1 + z2_ * (x * x + y * y));
    return cang <= 0.0 ? 1.0 : 1.0 + 254.0 * cang;
  }

 private:
  double sinAlt_, zCosAlt_, cosAz_, sinAz_, z2_;
};

}  // namespace rover::terrain
