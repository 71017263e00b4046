#pragma once
// Local frame (SPEC §0) -> longitude and latitude in degrees on the map's own body: the
// geographic CRS underlying the map's CRS (its datum and ellipsoid: the Moon's for a lunar map,
// not WGS 84). For position fixes (foxglove.LocationFix in the MCAP replay). Local -> map CRS is
// localToCrs (maps/georef.hpp), the one conversion the GeoJSON and CSV exports use; a projected
// CRS is then unprojected by PROJ through GDAL's OGRCoordinateTransformation.
#include <Eigen/Core>
#include <memory>
#include <optional>

#include "core/grid/raster.hpp"

namespace rover::maps {

class LonLatOfLocal {
 public:
  // nullopt when the map has no georeference or CRS, or when PROJ cannot unproject its CRS.
  static std::optional<LonLatOfLocal> make(const GridGeometry& g, const GeoReference& geo);
  // (longitude, latitude) in degrees; nullopt where the projection has no inverse.
  std::optional<Eigen::Vector2d> operator()(const Eigen::Vector2d& local) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;  // the transformation is not copied: shared, used read-only
};

}  // namespace rover::maps
