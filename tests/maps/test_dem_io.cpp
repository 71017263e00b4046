#include <doctest/doctest.h>

#include <gdal.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <limits>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/dem_digest.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("roverplan-test-" + std::to_string(::getpid()) + "-" +
                                        std::to_string(std::rand()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

// Writes a one-band GeoTIFF of `type` with values from f(row, col), the geotransform and EPSG code
// (0 = no CRS); nodata set when `nodata` is finite.
void writeTiff(const std::string& path, int rows, int cols, GDALDataType type,
               std::array<double, 6> gt, int epsg, const std::function<double(int, int)>& f,
               double nodata = NAN, double scale = 1.0) {
  maps::ensureGdal();
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), cols, rows, 1, type, nullptr);
  REQUIRE(ds);
  GDALSetGeoTransform(ds, gt.data());
  if (epsg) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(srs, epsg);
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
  }
  GDALRasterBandH b = GDALGetRasterBand(ds, 1);
  if (!std::isnan(nodata)) GDALSetRasterNoDataValue(b, nodata);
  if (scale != 1.0) GDALSetRasterScale(b, scale);
  std::vector<double> v(static_cast<std::size_t>(rows) * cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) v[static_cast<std::size_t>(r) * cols + c] = f(r, c);
  REQUIRE(GDALRasterIO(b, GF_Write, 0, 0, cols, rows, v.data(), cols, rows, GDT_Float64, 0, 0) == CE_None);
  GDALClose(ds);
}

// Smooth hills with every slope direction, on a UTM grid (square 0.5 m pixels).
double hills(int r, int c) {
  return 20 * std::sin(r * 0.05) * std::cos(c * 0.07) + 0.02 * r * c / 10.0 + 3 * std::sin(c * 0.3);
}

std::string errorOf(const std::string& path, const maps::LoadOptions& o = {}) {
  try {
    maps::loadDem(path, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

bool haveGdaldem() { return std::system("command -v gdaldem > /dev/null 2>&1") == 0; }

fs::path sharedDems() { return fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems"; }

}  // namespace

TEST_CASE("GeoTIFF round trip keeps values, nodata, geotransform and CRS") {
  TempDir tmp;
  const std::string in = tmp.file("in.tif");
  writeTiff(in, 30, 40, GDT_Float32, {500000, 0.5, 0, 4100000, 0, -0.5}, 32633, hills);
  maps::LoadedDem a = maps::loadDem(in);
  CHECK(a.info.driver == "GTiff");
  CHECK(a.dem.geometry().rows == 30);
  CHECK(a.dem.geometry().cellWidth == 0.5);
  CHECK(a.dem.z.geo.valid);
  CHECK(a.dem.z.geo.geotransform[0] == 500000);
  a.dem.z(3, 4) = NAN;
  const std::string out = tmp.file("out.tif");
  maps::writeGeoTiff(out, a.dem.z);
  CHECK_FALSE(fs::exists(out + ".tmp"));  // written atomically
  maps::LoadedDem b = maps::loadDem(out);
  CHECK(std::isnan(b.dem.z(3, 4)));
  CHECK(b.info.nodataCells == 1);
  CHECK(b.dem.z(10, 11) == a.dem.z(10, 11));
  CHECK(b.dem.z.geo.geotransform == a.dem.z.geo.geotransform);
  CHECK(b.info.crsName == a.info.crsName);
}

TEST_CASE("classes GeoTIFF carries a colour table and category names") {
  TempDir tmp;
  Raster<std::uint8_t> cls(GridGeometry{4, 5, 1, 1}, 0);
  cls(1, 1) = 2;
  cls(2, 2) = 3;
  const std::string out = tmp.file("classes.tif");
  maps::writeClassesGeoTiff(out, cls);
  GDALDatasetH ds = GDALOpen(out.c_str(), GA_ReadOnly);
  REQUIRE(ds);
  GDALRasterBandH b = GDALGetRasterBand(ds, 1);
  CHECK(GDALGetRasterDataType(b) == GDT_Byte);
  REQUIRE(GDALGetRasterColorTable(b));
  CHECK(GDALGetColorEntry(GDALGetRasterColorTable(b), 2)->c1 == 208);  // impassable red
  int has = 0;
  CHECK(GDALGetRasterNoDataValue(b, &has) == 3);
  char** names = GDALGetRasterCategoryNames(b);
  REQUIRE(names);
  CHECK(std::string(names[1]) == "high_risk");
  GDALClose(ds);
}

TEST_CASE("scale, nodata and vertical scale are applied") {
  TempDir tmp;
  const std::string in = tmp.file("int16.tif");
  writeTiff(in, 5, 5, GDT_Int16, {0, 10, 0, 50, 0, -10}, 32633,
            [](int r, int c) { return r == 0 && c == 0 ? -32768 : 100 * r + c; }, -32768, 0.5);
  maps::LoadedDem d = maps::loadDem(in);
  CHECK(std::isnan(d.dem.z(0, 0)));
  CHECK(d.dem.z(2, 3) == doctest::Approx(0.5 * 203));
  maps::LoadOptions o;
  o.verticalScale = 2.0;
  CHECK(maps::loadDem(in, o).dem.z(2, 3) == doctest::Approx(203));
}

TEST_CASE("south-up rasters come out north-up") {
  TempDir tmp;
  const std::string in = tmp.file("southup.tif");
  // Row 0 of the file is the southern edge: its values are the smallest.
  writeTiff(in, 6, 4, GDT_Float32, {0, 1, 0, 1000, 0, 1}, 32633, [](int r, int) { return r; });
  maps::LoadedDem d = maps::loadDem(in);
  CHECK(d.dem.z(0, 0) == 5.0f);  // northernmost first
  CHECK(d.dem.z(5, 0) == 0.0f);
  CHECK(d.dem.z.geo.geotransform[5] < 0);
  CHECK(d.dem.z.geo.geotransform[3] == doctest::Approx(1006));
}

TEST_CASE("geographic CRS: cell sizes in metres from the ellipsoid, per row") {
  TempDir tmp;
  const std::string in = tmp.file("geo.tif");
  // 0.001° pixels around 60°N on WGS84: ~111.4 m north-south, ~55.8 m east-west.
  writeTiff(in, 20, 20, GDT_Float32, {10, 0.001, 0, 60.01, 0, -0.001}, 4326, [](int, int c) { return c; });
  maps::LoadedDem d = maps::loadDem(in);
  CHECK(d.info.geographic);
  CHECK(d.dem.dy() == doctest::Approx(111.41).epsilon(0.002));
  CHECK(d.dem.dx(10) == doctest::Approx(55.8).epsilon(0.003));
  CHECK(d.dem.dx(0) < d.dem.dx(19));  // narrower towards the pole
  // A 1 m rise per column: slope atan(1 / dx) east-west, so the classes use the real spacing.
  auto t = terrain::traversability(d.dem, {}, true);
  CHECK(t.worstSlopeDeg(10, 10) == doctest::Approx(std::atan(1.0 / d.dem.dx(10)) * kDeg).epsilon(0.01));
}

TEST_CASE("crop and resample through GDAL's warper") {
  TempDir tmp;
  const std::string in = tmp.file("big.tif");
  writeTiff(in, 40, 60, GDT_Float32, {1000, 1, 0, 2040, 0, -1}, 32633, [](int r, int c) { return r + c; });
  maps::LoadOptions o;
  o.crop = std::array<double, 4>{1010, 2010, 20, 10};  // lower-left (1010, 2010), 20 × 10 m
  maps::LoadedDem c = maps::loadDem(in, o);
  CHECK(c.dem.geometry().cols == 20);
  CHECK(c.dem.geometry().rows == 10);
  CHECK(c.dem.z(0, 0) == 20.0f + 10.0f);  // top of the window: file row 20 (Y 2020), col 10
  o.crop.reset();
  o.cellSize = 2.0;
  maps::LoadedDem s = maps::loadDem(in, o);
  CHECK(s.info.resampling == "average");
  CHECK(s.dem.geometry().cols == 30);
  CHECK(s.dem.geometry().cellWidth == 2.0);
  CHECK(s.dem.z(0, 0) == doctest::Approx(1.0));  // mean of 0, 1, 1, 2
  o.cellSize = 0.5;
  CHECK(maps::loadDem(in, o).info.resampling == "bilinear");
  o.cellSize = 0;
  o.crop = std::array<double, 4>{0, 0, 10, 10};
  CHECK(errorOf(in, o) == in + ": the crop window lies outside the raster");
}

TEST_CASE("bad files get one clear error naming the file") {
  TempDir tmp;
  const std::string empty = tmp.file("empty.tif");
  std::ofstream(empty).close();
  CHECK(errorOf(empty) == empty + ": empty file");
  CHECK(errorOf(tmp.file("missing.tif")) == tmp.file("missing.tif") + ": no such file");
  const std::string text = tmp.file("notes.txt");
  std::ofstream(text) << "this is not a raster\n";
  CHECK(errorOf(text).rfind(text + ": not a raster GDAL can read", 0) == 0);

  const std::string good = tmp.file("good.tif");
  writeTiff(good, 64, 64, GDT_Float32, {0, 1, 0, 64, 0, -1}, 32633, hills);
  const std::string cut = tmp.file("truncated.tif");
  {
    std::ifstream src(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(src)), {});
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  std::string e = errorOf(cut);
  CHECK_MESSAGE(e.rfind(cut + ": ", 0) == 0, e);
  CHECK(e != "no error");

  maps::LoadOptions small;
  small.maxCells = 1000;
  CHECK(errorOf(good, small) == good + ": raster of 64 x 64 cells exceeds the cell budget of 1000");

  const std::string allNodata = tmp.file("nodata.tif");
  writeTiff(allNodata, 4, 4, GDT_Float32, {0, 1, 0, 4, 0, -1}, 32633, [](int, int) { return -9999; }, -9999);
  CHECK(errorOf(allNodata) == allNodata + ": every cell is nodata");

  const std::string inf = tmp.file("inf.tif");
  writeTiff(inf, 4, 4, GDT_Float32, {0, 1, 0, 4, 0, -1}, 32633,
            [](int r, int) { return r == 2 ? INFINITY : 1.0; });
  CHECK(errorOf(inf) == inf + ": the raster holds infinite values");

  const std::string nan = tmp.file("nan.tif");
  writeTiff(nan, 4, 4, GDT_Float32, {0, 1, 0, 4, 0, -1}, 32633, [](int r, int) { return r == 2 ? NAN : 1.0; });
  CHECK(maps::loadDem(nan).info.nodataCells == 4);  // NaN heights are nodata
}

TEST_CASE("Horn slope, aspect and hillshade agree with gdaldem on interior cells") {
  if (!haveGdaldem()) {
    MESSAGE("gdaldem not found (Debian gdal-bin): skipping the comparison");
    return;
  }
  TempDir tmp;
  const std::string in = tmp.file("hills.tif");
  writeTiff(in, 120, 150, GDT_Float32, {500000, 0.5, 0, 4100000, 0, -0.5}, 32633, hills);
  maps::LoadedDem d = maps::loadDem(in);
  auto gdaldem = [&](const std::string& mode) {
    const std::string out = tmp.file(mode + ".tif");
    std::string cmd = "gdaldem " + mode + " -q " + in + " " + out;
    REQUIRE(std::system(cmd.c_str()) == 0);
    return maps::loadDem(out).dem.z;
  };
  Raster<float> ours = terrain::slopeHorn(d.dem), ref = gdaldem("slope");
  double worst = 0;
  for (int r = 1; r < 119; ++r)
    for (int c = 1; c < 149; ++c) worst = std::max(worst, std::fabs(double(ours(r, c)) - ref(r, c)));
  CHECK(worst < 0.01);
  MESSAGE("max |slope - gdaldem slope| = " << worst << " deg");

  Raster<float> asp = terrain::aspectHorn(d.dem), refAsp = gdaldem("aspect");
  worst = 0;
  for (int r = 1; r < 119; ++r)
    for (int c = 1; c < 149; ++c) {
      if (std::isnan(refAsp(r, c))) continue;
      double diff = std::fabs(double(asp(r, c)) - refAsp(r, c));
      worst = std::max(worst, std::min(diff, 360 - diff));
    }
  CHECK(worst < 0.01);

  Raster<float> hs = terrain::hillshade(d.dem), refHs = gdaldem("hillshade");  // Byte output
  worst = 0;
  for (int r = 1; r < 119; ++r)
    for (int c = 1; c < 149; ++c) worst = std::max(worst, std::fabs(double(hs(r, c)) - refHs(r, c)));
  CHECK(worst <= 1.0);
}

TEST_CASE("every DEM in ../shared/dems loads and gives sensible layers") {
  const fs::path dir = sharedDems();
  if (!fs::exists(dir)) {
    MESSAGE("SKIPPED: " << dir.string() << " is absent (a user's clone): real-DEM suite not run");
    return;
  }
  struct Case {
    const char* file;
    int rows, cols;
    double cellMin, cellMax;  // metres
  };
  const Case cases[] = {
      {"mars_gale_hirise_1m/missionDEM.tif", 337, 348, 0.99, 1.01},
      {"moon_lola_kepler_crater/kepler.tif", 804, 804, 47, 48.5},
      {"moon_lola_ldem4_global/LDEM_4.IMG", 720, 1440, 7000, 7600},
      {"moon_lola_ldem4_global/LDEM_4.LBL", 720, 1440, 7000, 7600},
      {"earth_luxembourg_srtm/elev.tif", 90, 95, 590, 610},
  };
  for (const Case& k : cases) {
    CAPTURE(k.file);
    maps::LoadedDem d = maps::loadDem((dir / k.file).string());
    CHECK(d.dem.geometry().rows == k.rows);
    CHECK(d.dem.geometry().cols == k.cols);
    CHECK(d.dem.geometry().cellWidth >= k.cellMin);
    CHECK(d.dem.geometry().cellWidth <= k.cellMax);
    auto t = terrain::traversability(d.dem);
    using TC = terrain::TerrainClass;
    // Real terrain: mostly traversable or steep, never a constant.
    CHECK(t.shares.percent(TC::Traversable) > 20);
    CHECK(t.shares.percent(TC::Impassable) < 60);
    CHECK(d.info.maxHeight > d.info.minHeight);
  }
  // Luxembourg is geographic WGS84 with nodata outside the country.
  maps::LoadedDem lux = maps::loadDem((dir / "earth_luxembourg_srtm/elev.tif").string());
  CHECK(lux.info.geographic);
  CHECK(lux.info.nodataCells > 1000);
  CHECK(lux.dem.dy() == doctest::Approx(926.9).epsilon(0.002));
  // The global LOLA map's scale (0.5 m per DN) comes from the PDS label.
  maps::LoadedDem lola = maps::loadDem((dir / "moon_lola_ldem4_global/LDEM_4.LBL").string());
  CHECK(lola.info.scale == 0.5);
  // Equirectangular: pixels near the poles are narrow on the ground.
  CHECK(lola.dem.dx(0) < 0.01 * lola.dem.dx(360));
}

TEST_CASE("Horn slope agrees with gdaldem on the real Kepler crater DEM") {
  const fs::path kepler = sharedDems() / "moon_lola_kepler_crater/kepler.tif";
  if (!fs::exists(kepler) || !haveGdaldem()) {
    MESSAGE("SKIPPED: Kepler DEM or gdaldem absent");
    return;
  }
  TempDir tmp;
  const std::string out = tmp.file("kslope.tif");
  REQUIRE(std::system(("gdaldem slope -q " + kepler.string() + " " + out).c_str()) == 0);
  Raster<float> ours = terrain::slopeHorn(maps::loadDem(kepler.string()).dem);
  Raster<float> ref = maps::loadDem(out).dem.z;
  double worst = 0;
  for (int r = 1; r < 803; ++r)
    for (int c = 1; c < 803; ++c) worst = std::max(worst, std::fabs(double(ours(r, c)) - ref(r, c)));
  CHECK(worst < 0.01);
}

TEST_CASE("dem digest: the SHA-256 of the grid as defined, whatever the NaN payload") {
  terrain::Dem d;
  d.z = Raster<float>(GridGeometry{2, 3, 1.0, 0.5}, 0.0f);
  const float v[6] = {1, 2, 3, 4, 5, std::numeric_limits<float>::quiet_NaN()};
  for (int i = 0; i < 6; ++i) d.z.at(i) = v[i];
  // Python: sha256(b'roverplan-dem-v1' + struct.pack('<qqddq', 2, 3, 1.0, 0.5, 0)
  //                + struct.pack('<6f', 1, 2, 3, 4, 5, float('nan')))
  CHECK(maps::demSha256(d) == "9c2233b4be5cbbd45ea3db1d6dd7587a1b0f99b30b66fd04385c78192a0261b4");
  terrain::Dem e = d;
  e.z.at(5) = -std::numeric_limits<float>::quiet_NaN();  // another NaN: the same nodata cell
  CHECK(maps::demSha256(e) == maps::demSha256(d));
  e.z.at(0) = 1.0001f;
  CHECK(maps::demSha256(e) != maps::demSha256(d));
  e = d;
  e.rowCellWidth = {1.0, 1.0};  // per-row widths are part of the ground
  CHECK(maps::demSha256(e) != maps::demSha256(d));
}

TEST_CASE("heights read in bands on every core: nodata, scale and figures over the whole grid, an infinity in a late band") {
  // 2100 x 2100 cells: two bands of readHeights' 4 Mi cells, the second one cut.
  TempDir tmp;
  const int n = 2100;
  const std::string path = tmp.file("big.tif");
  writeTiff(path, n, n, GDT_Float32, {0, 1, 0, double(n), 0, -1}, 32633, [&](int r, int c) {
    if ((r * 31 + c) % 101 == 0) return -9999.0;  // nodata in both bands
    if (r == 2 && c == 3) return -40.0;            // the lowest, in the first band
    if (r == n - 1 && c == n - 2) return 900.0;    // the highest, in the second
    return 10.0 + (r + c) % 50;
  }, -9999);
  std::int64_t nodata = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) nodata += (r * 31 + c) % 101 == 0 ? 1 : 0;
  maps::LoadOptions o;
  o.verticalScale = 2;
  const maps::LoadedDem d = maps::loadDem(path, o);
  CHECK(d.info.nodataCells == nodata);
  CHECK(d.info.minHeight == -80.0);
  CHECK(d.info.maxHeight == 1800.0);
  CHECK(std::isnan(d.dem.z(0, 0)));
  CHECK(d.dem.z(n - 1, n - 2) == 1800.0f);

  const std::string inf = tmp.file("inf-late.tif");
  writeTiff(inf, n, n, GDT_Float32, {0, 1, 0, double(n), 0, -1}, 32633,
            [&](int r, int c) { return r == n - 3 && c == 7 ? INFINITY : 1.0; });
  CHECK(errorOf(inf) == inf + ": the raster holds infinite values");
}
