#pragma once
// Values as a GeoTIFF a GIS can compute with (issue 27: the mission export was an RGBA picture):
// one Float32 band per quantity, each with its description, one nodata value for all, in the
// map's CRS. DEFLATE-compressed, written band after band.
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid/raster.hpp"
#include "maps/geojson.hpp"

namespace rover::maps {

struct ValueBand {
  std::string description;  // e.g. "elevation (m)"
  Raster<float> values;     // row 0 north; NaN = no value (written as the nodata value)
};

inline constexpr double kValueNoData = -9999.0;

// Every band must have the same rows and columns. `geo` georeferences the map's own grid
// `mapGrid`; the bands' grid spans the same extent (a map over the export's size cap is given
// resampled). Throws std::runtime_error when GDAL fails.
std::vector<std::uint8_t> encodeValueGeoTiff(const std::vector<ValueBand>& bands, const GridGeometry& mapGrid,
                                             const GeoReference& geo);

}  // namespace rover::maps
