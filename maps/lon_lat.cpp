#include "maps/lon_lat.hpp"

#include <ogr_spatialref.h>

#include <cmath>

#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::maps {

struct LonLatOfLocal::Impl {
  GridGeometry grid;
  GeoReference geo;
  double degreesPerUnit = 1.0;  // a geographic map: its CRS unit in degrees
  // A projected map: map CRS -> its geographic CRS, longitude first; null for a geographic map.
  std::unique_ptr<OGRCoordinateTransformation> toGeographic;
};

std::optional<LonLatOfLocal> LonLatOfLocal::make(const GridGeometry& g, const GeoReference& geo) {
  if (!geo.valid || geo.crsWkt.empty()) return std::nullopt;
  ensureGdal();
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(geo.crsWkt.c_str(), OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) != OGRERR_NONE)
    return std::nullopt;
  // localToCrs answers in the geotransform's axis order (x = easting or longitude): the GIS order.
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  auto impl = std::make_shared<Impl>();
  impl->grid = g;
  impl->geo = geo;
  if (srs.IsGeographic()) {
    impl->degreesPerUnit = crsUnits(OGRSpatialReference::ToHandle(&srs)).degreesPerUnit;
  } else {
    std::unique_ptr<OGRSpatialReference> geographic(srs.CloneGeogCS());
    if (!geographic) return std::nullopt;
    geographic->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    impl->toGeographic.reset(OGRCreateCoordinateTransformation(&srs, geographic.get()));
    if (!impl->toGeographic) return std::nullopt;
  }
  LonLatOfLocal out;
  out.impl_ = std::move(impl);
  return out;
}

std::optional<Eigen::Vector2d> LonLatOfLocal::operator()(const Eigen::Vector2d& local) const {
  const Eigen::Vector2d c = localToCrs(impl_->grid, impl_->geo, local);
  double x = c.x(), y = c.y();
  if (impl_->toGeographic) {
    if (!impl_->toGeographic->Transform(1, &x, &y)) return std::nullopt;
  } else {
    x *= impl_->degreesPerUnit;
    y *= impl_->degreesPerUnit;
  }
  if (!std::isfinite(x) || !std::isfinite(y)) return std::nullopt;
  return Eigen::Vector2d(x, y);
}

}  // namespace rover::maps
