// The decoded blocks the stored rasters' handles share (maps/block_cache.hpp): a window read
// through them is exactly GDALRasterIO's, at every level, across block edges and in the cut last
// blocks; a file rewritten at the same path is read anew; other drivers are left to GDAL.
#include <doctest/doctest.h>

#include <gdal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <filesystem>
#include <string>
#include <vector>

#include "maps/block_cache.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/gdal_env.hpp"

using namespace rover;
using namespace rover::maps;
namespace fs = std::filesystem;

namespace {

struct Scratch {
  fs::path path = fs::temp_directory_path() / ("roverplan-blocks-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(path); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

Raster<float> ramp(int rows, int cols, float offset) {
  Raster<float> r(GridGeometry{rows, cols, 1.0, 1.0}, 0.0f);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) r(i, j) = offset + 0.37f * i * i - 1.3f * j + (i * 7 + j) % 11;
  r(3, 4) = std::numeric_limits<float>::quiet_NaN();
  return r;
}

struct Opened {
  Dataset ds;
  struct stat id {};
  explicit Opened(const std::string& path)
      : ds(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)) {
    REQUIRE(ds);
    REQUIRE(::stat(path.c_str(), &id) == 0);
  }
};

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The window through the shared blocks and through GDALRasterIO, on `band` of `file`.
void checkWindow(const Opened& file, const std::string& path, GDALRasterBandH band, int c0, int r0, int cols, int rows) {
  std::vector<float> cached(std::size_t(cols) * rows, -1.0f), gdal(cached.size(), -2.0f);
  REQUIRE(readThroughBlocks(file.ds.get(), band, path, file.id, c0, r0, cols, rows, cached.data(), GDT_Float32));
  REQUIRE(GDALRasterIO(band, GF_Read, c0, r0, cols, rows, gdal.data(), cols, rows, GDT_Float32, 0, 0) == CE_None);
  CHECK(sameBits(cached, gdal));
}

}  // namespace

TEST_CASE("block cache: windows through the shared blocks are GDAL's own, at every level and the cut edges") {
  ensureGdal();
  Scratch dir;
  const std::string path = (dir.path / "dem.tif").string();
  writeDemCog(path, ramp(700, 530, 0));  // 128² blocks: 530 columns cut the fifth block column
  const Opened a(path), b(path);  // two handles: the second reads what the first decoded
  GDALRasterBandH base = GDALGetRasterBand(a.ds.get(), 1);
  checkWindow(a, path, base, 0, 0, 530, 700);       // everything
  checkWindow(a, path, base, 127, 255, 258, 258);   // a tile's window with its halo across 4 × 4 blocks
  checkWindow(b, path, GDALGetRasterBand(b.ds.get(), 1), 127, 255, 258, 258);
  checkWindow(b, path, GDALGetRasterBand(b.ds.get(), 1), 500, 690, 30, 10);  // the cut corner block
  checkWindow(a, path, base, 3, 4, 1, 1);           // the NaN cell
  REQUIRE(GDALGetOverviewCount(base) == 2);
  for (int i = 0; i < 2; ++i) {
    GDALRasterBandH o = GDALGetOverview(base, i);
    checkWindow(a, path, o, 0, 0, GDALGetRasterBandXSize(o), GDALGetRasterBandYSize(o));
    checkWindow(b, path, GDALGetOverview(GDALGetRasterBand(b.ds.get(), 1), i), 1, 1, 100, 120);
  }
  // Another type than the band's, or a window outside it: left to GDAL.
  std::vector<std::uint8_t> bytes(16);
  CHECK_FALSE(readThroughBlocks(a.ds.get(), base, path, a.id, 0, 0, 4, 4, bytes.data(), GDT_Byte));
  std::vector<float> cells(16);
  CHECK_FALSE(readThroughBlocks(a.ds.get(), base, path, a.id, 528, 0, 4, 4, cells.data(), GDT_Float32));
}

TEST_CASE("block cache: a file rewritten at the same path reads its new cells; other drivers are GDAL's") {
  ensureGdal();
  Scratch dir;
  const std::string path = (dir.path / "dem.tif").string();
  writeDemCog(path, ramp(300, 200, 0));
  {
    const Opened a(path);
    checkWindow(a, path, GDALGetRasterBand(a.ds.get(), 1), 0, 0, 200, 300);
  }
  // Rewritten (another inode): its blocks are not the old file's even at the same path.
  writeDemCog(path, ramp(300, 200, 1000));
  {
    const Opened a(path);
    std::vector<float> v(1);
    REQUIRE(readThroughBlocks(a.ds.get(), GDALGetRasterBand(a.ds.get(), 1), path, a.id, 10, 10, 1, 1, v.data(),
                              GDT_Float32));
    CHECK(v[0] == ramp(300, 200, 1000)(10, 10));
    checkWindow(a, path, GDALGetRasterBand(a.ds.get(), 1), 0, 0, 200, 300);
  }
  forgetDecodedBlocks(dir.path.string());  // a deleted map's blocks: dropped, and read anew after
  {
    const Opened a(path);
    checkWindow(a, path, GDALGetRasterBand(a.ds.get(), 1), 60, 60, 100, 100);
  }
  // A VRT over the COG: GDAL reads it (the cache keys GeoTIFF blocks only).
  const std::string vrt = (dir.path / "dem.vrt").string();
  {
    const Opened src(path);
    Dataset v(GDALCreateCopy(GDALGetDriverByName("VRT"), vrt.c_str(), src.ds.get(), FALSE, nullptr, nullptr, nullptr));
    REQUIRE(v);
  }
  const Opened v(vrt);
  std::vector<float> cells(4);
  CHECK_FALSE(readThroughBlocks(v.ds.get(), GDALGetRasterBand(v.ds.get(), 1), vrt, v.id, 0, 0, 2, 2, cells.data(),
                                GDT_Float32));
}
