// LayerBands (maps/layer_bands.hpp): a stored DEM's elevation, slope and hillshade band by band,
// bit for bit the whole map's layers, on a geographic map (a cell width per row) with a numeric
// nodata value and rows that are not a multiple of the band.
#include <doctest/doctest.h>

#include <gdal.h>
#include <ogr_srs_api.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/layer_bands.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

struct TempFile {
  std::string path = (fs::temp_directory_path() / ("roverplan-bands-" + std::to_string(::getpid()) + ".tif")).string();
  ~TempFile() {
    std::error_code ec;
    fs::remove(path, ec);
  }
};

// 530 × 70 cells of 0.001° around 60°N (WGS84), nodata -9999 in a block across rows 254..258
// and along the first row's left part; blocks of 128 rows, as the stored COGs have.
void writeGeographic(const std::string& path, double scale = 1.0) {
  maps::ensureGdal();
  const int rows = 530, cols = 70;
  const char* options[] = {"TILED=YES", "BLOCKXSIZE=128", "BLOCKYSIZE=128", nullptr};
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), cols, rows, 1, GDT_Float32,
                               const_cast<char**>(options));
  REQUIRE(ds);
  double gt[6] = {10, 0.001, 0, 60.3, 0, -0.001};
  GDALSetGeoTransform(ds, gt);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, 4326);
  GDALSetSpatialRef(ds, srs);
  OSRDestroySpatialReference(srs);
  GDALRasterBandH b = GDALGetRasterBand(ds, 1);
  GDALSetRasterNoDataValue(b, -9999);
  if (scale != 1.0) GDALSetRasterScale(b, scale);
  std::vector<float> v(std::size_t(rows) * cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      v[std::size_t(r) * cols + c] = (r >= 254 && r <= 258 && c >= 20 && c < 30) || (r == 0 && c < 10)
                                         ? -9999.0f
                                         : static_cast<float>(300 * std::sin(0.05 * c) * std::cos(0.013 * r) + 2.0 * c);
  REQUIRE(GDALRasterIO(b, GF_Write, 0, 0, cols, rows, v.data(), cols, rows, GDT_Float32, 0, 0) == CE_None);
  GDALClose(ds);
}

// Every band of `layer` one after the other.
std::vector<float> allBands(const std::string& path, maps::RenderLayer layer) {
  maps::LayerBands bands(path, maps::readDemHeader(path), layer);
  const GridGeometry& g = bands.geometry();
  std::vector<float> out(std::size_t(g.rows) * g.cols);
  std::vector<float> band(std::size_t(maps::LayerBands::kBandRows) * g.cols);
  std::size_t at = 0;
  while (const int n = bands.next(band.data())) {
    CHECK(n <= maps::LayerBands::kBandRows);
    REQUIRE(at + std::size_t(n) * g.cols <= out.size());
    std::copy_n(band.data(), std::size_t(n) * g.cols, out.data() + at);
    at += std::size_t(n) * g.cols;
  }
  CHECK(at == out.size());
  CHECK(bands.next(band.data()) == 0);
  return out;
}

bool sameBits(const std::vector<float>& a, const Raster<float>& b) {
  return a.size() == std::size_t(b.values.size()) && std::memcmp(a.data(), b.values.data(), a.size() * 4) == 0;
}

}  // namespace

TEST_CASE("layer bands: elevation, slope and hillshade of a geographic map with nodata are the whole map's, "
          "bit for bit") {
  TempFile f;
  writeGeographic(f.path);
  const terrain::Dem dem = maps::loadDem(f.path).dem;
  REQUIRE_FALSE(dem.rowCellWidth.empty());  // a cell width per row
  REQUIRE(dem.rowCellWidth.front() != dem.rowCellWidth.back());
  REQUIRE(std::isnan(dem.z(256, 25)));
  CHECK(sameBits(allBands(f.path, maps::RenderLayer::Elevation), dem.z));
  const Raster<float> slope = terrain::slopeHorn(dem);
  CHECK(sameBits(allBands(f.path, maps::RenderLayer::Slope), slope));
  CHECK(sameBits(allBands(f.path, maps::RenderLayer::Hillshade), terrain::hillshade(dem)));
  // Not vacuous: values on both sides of the band boundary, nodata beside the holes.
  CHECK(slope(255, 10) > 0.0f);
  CHECK(slope(256, 10) > 0.0f);
  CHECK(std::isnan(slope(253, 25)));
  CHECK(std::isnan(slope(1, 5)));
}

TEST_CASE("layer bands: other layers and a raster that is not a stored map's are refused") {
  TempFile f;
  writeGeographic(f.path, 0.5);
  const maps::DemHeader header = maps::readDemHeader(f.path);
  CHECK_THROWS_AS(maps::LayerBands(f.path, header, maps::RenderLayer::Traversability), Error);
  CHECK_THROWS_AS(maps::LayerBands(f.path, header, maps::RenderLayer::Slope), std::runtime_error);  // a scale
  maps::DemHeader other = header;
  other.geometry.rows += 1;
  CHECK_THROWS_AS(maps::LayerBands(f.path, other, maps::RenderLayer::Slope), std::runtime_error);
}
