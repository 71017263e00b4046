#include "maps/value_geotiff.hpp"

#include <gdal.h>

#include <atomic>
#include <cmath>
#include <stdexcept>

#include "maps/gdal_env.hpp"

namespace rover::maps {

std::vector<std::uint8_t> encodeValueGeoTiff(const std::vector<ValueBand>& bands, const GridGeometry& mapGrid,
                                             const GeoReference& geo) {
  if (bands.empty()) throw std::runtime_error("GeoTIFF export: no band");
  const GridGeometry& g = bands.front().values.geometry;
  for (const auto& b : bands)
    if (b.values.geometry.rows != g.rows || b.values.geometry.cols != g.cols)
      throw std::runtime_error("GeoTIFF export: bands of different sizes");
  ensureGdal();
  GDALDriverH gtiff = GDALGetDriverByName("GTiff");
  if (gtiff == nullptr) throw std::runtime_error("GeoTIFF export: GDAL lacks the GTiff driver");
  static std::atomic<unsigned long long> counter{0};
  const std::string path = "/vsimem/rover_value_bands_" + std::to_string(counter.fetch_add(1)) + ".tif";
  // Band-interleaved (one band written at a time), predictor 3 for floating point.
  const char* options[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "INTERLEAVE=BAND", "TILED=YES", nullptr};
  GDALDatasetH ds = GDALCreate(gtiff, path.c_str(), g.cols, g.rows, static_cast<int>(bands.size()), GDT_Float32,
                               const_cast<char**>(options));
  if (ds == nullptr) throw std::runtime_error(std::string("GeoTIFF export: ") + CPLGetLastErrorMsg());
  CPLErr err = CE_None;
  std::vector<float> row(static_cast<std::size_t>(g.cols));
  for (std::size_t k = 0; k < bands.size() && err == CE_None; ++k) {
    GDALRasterBandH band = GDALGetRasterBand(ds, static_cast<int>(k) + 1);
    GDALSetDescription(band, bands[k].description.c_str());
    err = GDALSetRasterNoDataValue(band, kValueNoData);
    for (int r = 0; r < g.rows && err == CE_None; ++r) {
      for (int c = 0; c < g.cols; ++c) {
        const float v = bands[k].values(r, c);
        row[static_cast<std::size_t>(c)] = std::isfinite(v) ? v : static_cast<float>(kValueNoData);
      }
      err = GDALRasterIO(band, GF_Write, 0, r, g.cols, 1, row.data(), g.cols, 1, GDT_Float32, 0, 0);
    }
  }
  if (geo.valid && err == CE_None) {
    // The same extent as the map's own grid, at the bands' cell.
    const double sx = double(mapGrid.cols) / g.cols, sy = double(mapGrid.rows) / g.rows;
    double gt[6] = {geo.geotransform[0], geo.geotransform[1] * sx, geo.geotransform[2] * sy,
                    geo.geotransform[3], geo.geotransform[4] * sx, geo.geotransform[5] * sy};
    err = GDALSetGeoTransform(ds, gt);
    if (err == CE_None && !geo.crsWkt.empty()) err = GDALSetProjection(ds, geo.crsWkt.c_str());
  }
  GDALClose(ds);
  std::vector<std::uint8_t> bytes = takeMemFile(path);
  if (err != CE_None || bytes.empty()) throw std::runtime_error(std::string("GeoTIFF export: ") + CPLGetLastErrorMsg());
  return bytes;
}

}  // namespace rover::maps
