// libFuzzer harness for georeferencing and import options (issue 22). Bytes ->
//   1. a geotransform (6 doubles), a raster size and CRS units -> maps::georefProblem: when it
//      accepts, the pixel sides must be finite metres in [1 mm, 100 km] and every corner finite and
//      inside the bounds (latitude ±90°, longitude ±360°, ±1e8 m), one pixel of slack;
//   2. the same geotransform on a 6 × 5 GeoTIFF in /vsimem/ (geographic WGS 84, UTM, or none) ->
//      maps::loadDem under an UploadSandbox, as the import worker reads it: when it loads, the
//      grid's cells must pass core's checkGridGeometry (no planner can see a NaN cell size);
//   3. the rest as `key=value` lines -> maps::parseDemImportOptions: when it accepts, the cell,
//      crop and vertical scale must be inside their documented ranges.
// Expected refusals (rover::Error) are fine; a crash, a sanitizer report, a broken invariant
// (abort) or any other exception is a finding.
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>

#include "core/common/error.hpp"
#include "core/grid/geometry.hpp"
#include "maps/dem_import_options.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

using namespace rover;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

void checkAccepted(const std::array<double, 6>& gt, int rows, int cols, const maps::CrsUnits& u) {
  const double w = std::hypot(gt[1], gt[4]) * u.metresPerUnit, h = std::hypot(gt[2], gt[5]) * u.metresPerUnit;
  require(w >= maps::kMinPixelMetres && w <= maps::kMaxPixelMetres);
  require(h >= maps::kMinPixelMetres && h <= maps::kMaxPixelMetres);
  for (double c : {0.0, static_cast<double>(cols)})
    for (double r : {0.0, static_cast<double>(rows)}) {
      const double x = gt[0] + c * gt[1] + r * gt[2], y = gt[3] + c * gt[4] + r * gt[5];
      require(std::isfinite(x) && std::isfinite(y));
      if (u.geographic) {
        require(std::fabs(y * u.degreesPerUnit) <= 90 + std::hypot(gt[2], gt[5]) * u.degreesPerUnit);
        require(std::fabs(x * u.degreesPerUnit) <= 360 + std::hypot(gt[1], gt[4]) * u.degreesPerUnit);
      } else {
        require(std::fabs(x * u.metresPerUnit) <= maps::kMaxProjectedMetres);
        require(std::fabs(y * u.metresPerUnit) <= maps::kMaxProjectedMetres);
      }
    }
}

void loadThroughGdal(const std::array<double, 6>& gt, int crs) {
  static int n = 0;
  const std::string root = "/vsimem/fuzz_georef_" + std::to_string(++n);
  const std::string path = root + "/g.tif";
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 6, 5, 1, GDT_Float32, nullptr);
  if (!ds) return;
  double t[6];
  std::copy(gt.begin(), gt.end(), t);
  GDALSetGeoTransform(ds, t);
  if (crs) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(srs, crs);
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
  }
  float z[30];
  for (int i = 0; i < 30; ++i) z[i] = static_cast<float>(i % 7);
  (void)GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 6, 5, z, 6, 5, GDT_Float32, 0, 0);
  GDALClose(ds);
  {
    maps::UploadSandbox sandbox(root);
    maps::LoadOptions o;
    o.upload = &sandbox;
    o.maxCells = 1 << 16;
    try {
      const maps::LoadedDem d = maps::loadDem(path, o);
      checkGridGeometry(d.dem.geometry());  // throws (a finding) for a NaN or zero cell
      for (double w : d.dem.rowCellWidth) require(std::isfinite(w) && w > 0);
    } catch (const Error& e) {
      // A georeferencing refusal names its part; others are the file's (too large, …).
      require(e.field() != "map");
    }
  }
  VSIRmdirRecursive(root.c_str());
}

void parseOptions(const std::string& text) {
  std::map<std::string, std::string> values;
  std::size_t at = 0;
  while (at <= text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(at, end - at);
    const std::size_t eq = line.find('=');
    if (eq != std::string::npos) values[line.substr(0, eq)] = line.substr(eq + 1);
    at = end + 1;
  }
  try {
    const maps::DemImport d = maps::parseDemImportOptions(values);
    const auto& l = d.load;
    require(l.cellSize == 0 || (l.cellSize >= 1e-3 && l.cellSize <= 1e5));
    require(std::isfinite(l.verticalScale) && l.verticalScale != 0 && std::fabs(l.verticalScale) <= 1e6);
    for (const auto& w : {l.crop, l.cropPixels})
      if (w) require(std::isfinite((*w)[0] + (*w)[1] + (*w)[2] + (*w)[3]) && (*w)[2] > 0 && (*w)[3] > 0);
    require(!(l.crop && l.cropPixels));
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  maps::ensureGdal();
  if (size < 6 * 8 + 5) {
    parseOptions(std::string(reinterpret_cast<const char*>(data), size));
    return 0;
  }
  std::array<double, 6> gt;
  std::memcpy(gt.data(), data, 48);
  const int rows = 1 + (data[48] | (data[49] << 8)) % 40000, cols = 1 + (data[50] | (data[51] << 8)) % 40000;
  const std::uint8_t flags = data[52];
  maps::CrsUnits u;
  u.geographic = flags & 1;
  if (u.geographic) {
    u.degreesPerUnit = (flags & 2) ? 180 / M_PI : 1.0;  // radians or degrees
    u.metresPerUnit = u.degreesPerUnit * M_PI / 180 * ((flags & 4) ? 1737400.0 : 6378137.0);
  } else {
    u.metresPerUnit = (flags & 2) ? 0.3048 : 1.0;  // feet or metres
  }
  if (!maps::georefProblem(gt, rows, cols, u)) checkAccepted(gt, rows, cols, u);
  loadThroughGdal(gt, (flags & 8) ? 0 : u.geographic ? 4326 : 32633);
  parseOptions(std::string(reinterpret_cast<const char*>(data) + 53, size - 53));
  return 0;
}
