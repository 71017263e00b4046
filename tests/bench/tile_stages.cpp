// Where a cold tile's CPU goes (issue 24), printed, never asserted:
//   bench_tile_stages DEM.tif [--tiles N] [--rgba]
// Stores DEM.tif as a server import does (the COG and the class pyramid, in a scratch folder),
// then renders N tiles of each layer at the native zoom (the addresses tile_latency.py asks) plus
// zooms 0..2, one thread, and prints per layer the CPU (this thread's clock, so a loaded machine
// shifts it little) of each stage of a tile: reading its blocks from the pyramid, rendering
// (kernel, colour ramp, placing), encoding the PNG (the server's smallest colour type, or RGBA
// with --rgba); the mean PNG size and the PNG colour types used; and a
// digest of every tile's RGBA pixels, to compare two builds' pictures. Every PNG is decoded again
// with GDAL (outside the clocks) and must give the rendered RGBA: "decoded != rendered" counts
// those that do not.
#include <cpl_vsi.h>
#include <gdal.h>
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/terrain/layers.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/gdal_env.hpp"
#include "maps/map_tiles.hpp"
#include "maps/render.hpp"

namespace fs = std::filesystem;
using namespace rover;
using namespace rover::maps;

namespace {

double cpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

// The pyramid's reads, timed.
class TimedBlocks final : public TileBlocks {
 public:
  template <class F>
  auto timed(F&& f) const {
    const double t = cpuMs();
    auto r = f();
    ms += cpuMs() - t;
    return r;
  }
  explicit TimedBlocks(const TileBlocks& inner) : inner_(inner) {}
  terrain::Dem dem(int step, const BlockSpan& s) const override { return timed([&] { return inner_.dem(step, s); }); }
  Raster<std::uint8_t> classes(int step, const BlockSpan& s) const override {
    return timed([&] { return inner_.classes(step, s); });
  }
  Raster<float> pdm(int step, const BlockSpan& s) const override { return timed([&] { return inner_.pdm(step, s); }); }
  ColourRange range() const override { return inner_.range(); }
  mutable double ms = 0;

 private:
  const TileBlocks& inner_;
};

// RGBA of a PNG as GDAL decodes it (a palette expanded, grey repeated, missing alpha opaque).
std::vector<std::uint8_t> decode(const std::vector<std::uint8_t>& png, int& colourType) {
  colourType = png.size() > 25 ? png[25] : -1;
  const std::string path = "/vsimem/tile_stages.png";
  VSIFCloseL(VSIFileFromMemBuffer(path.c_str(), const_cast<GByte*>(png.data()), png.size(), FALSE));
  GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  std::vector<std::uint8_t> rgba;
  if (ds) {
    const int w = GDALGetRasterXSize(ds), h = GDALGetRasterYSize(ds), bands = GDALGetRasterCount(ds);
    rgba.assign(std::size_t(w) * h * 4, 255);
    std::vector<std::uint8_t> band(std::size_t(w) * h);
    for (int b = 1; b <= bands; ++b) {
      GDALRasterBandH hb = GDALGetRasterBand(ds, b);
      if (GDALRasterIO(hb, GF_Read, 0, 0, w, h, band.data(), w, h, GDT_Byte, 0, 0) != CE_None) return {};
      GDALColorTableH ct = GDALGetRasterColorTable(hb);
      for (std::size_t i = 0; i < band.size(); ++i) {
        if (ct) {
          const GDALColorEntry* e = GDALGetColorEntry(ct, band[i]);
          rgba[i * 4] = e->c1, rgba[i * 4 + 1] = e->c2, rgba[i * 4 + 2] = e->c3, rgba[i * 4 + 3] = e->c4;
        } else if (bands <= 2 && b == 1) {
          rgba[i * 4] = rgba[i * 4 + 1] = rgba[i * 4 + 2] = band[i];
        } else {
          rgba[i * 4 + (bands <= 2 ? 3 : b - 1)] = band[i];
        }
      }
    }
    GDALClose(ds);
  }
  VSIUnlink(path.c_str());
  return rgba;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_tile_stages DEM.tif [--tiles N] [--rgba]\n");
    return 2;
  }
  int ntiles = 128;
  PngColours colours = PngColours::Smallest;  // what the server's tiles use
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i]) == "--tiles" && i + 1 < argc) ntiles = std::atoi(argv[++i]);
    else if (std::string(argv[i]) == "--rgba") colours = PngColours::Rgba;
  ensureGdal();
  const fs::path work = fs::temp_directory_path() / ("tile-stages-" + std::to_string(::getpid()));
  fs::create_directories(work);
  const std::string demPath = (work / "dem.tif").string(), classPath = (work / "classes.tif").string();
  ColourRange range;
  {
    const LoadedDem d = loadDem(argv[1]);
    writeDemCog(demPath, d.dem.z);
    writeClassPyramid(classPath, terrain::traversability(d.dem).classes);
    range = colourRange(RenderLayer::Elevation, d.dem.z);
  }
  const auto header = std::make_shared<const DemHeader>(readDemHeader(demPath));
  const PyramidBlocks pyramid(demPath, classPath, header, range);
  const TileGrid grid = tileGridOf(header->geometry.rows, header->geometry.cols);
  const int n = grid.nativeZoom, across = tilesAcross(grid, n), down = tilesDown(grid, n);
  std::printf("%d x %d map, native zoom %d, %d tiles a layer (one thread, CPU ms a tile)\n", grid.rows, grid.cols, n,
              ntiles);
  std::printf("%-15s %6s %7s %7s %7s %9s %6s %18s %s\n", "layer", "read", "render", "encode", "total", "mean KiB",
              "types", "RGBA digest", "decoded != rendered");
  double all = 0;
  int allTiles = 0;
  for (auto layer : {RenderLayer::Elevation, RenderLayer::Slope, RenderLayer::Hillshade, RenderLayer::Traversability}) {
    std::vector<TileWindow> windows;
    for (int k = 0; k < ntiles; ++k)
      windows.push_back(*tileWindow(grid, n, (k * 7) % across, (k * 3 + k / across) % down));
    for (int z = 0; z < std::min(3, n); ++z) windows.push_back(*tileWindow(grid, z, 0, 0));
    TimedBlocks blocks(pyramid);
    double render = 0, encode = 0, bytes = 0;
    std::uint64_t digest = 1469598103934665603ull;  // FNV-1a over every tile's RGBA
    int wrong = 0;
    unsigned types = 0;  // bit per PNG colour type used
    for (const auto& w : windows) {
      const double t0 = cpuMs();
      const Image tile = renderTile(layer, blocks, w);
      const double t1 = cpuMs();
      const auto png = encodePng(tile, colours);
      encode += cpuMs() - t1;
      render += t1 - t0;
      bytes += png.size();
      for (std::uint8_t b : tile.rgba) digest = (digest ^ b) * 1099511628211ull;
      int type = 0;
      wrong += decode(png, type) != tile.rgba;
      types |= 1u << type;
    }
    render -= blocks.ms;
    const double k = double(windows.size());
    std::string typeList;
    for (int t = 0; t < 8; ++t)
      if (types & (1u << t)) {
        if (!typeList.empty()) typeList.push_back(',');
        typeList.push_back(static_cast<char>('0' + t));
      }
    std::printf("%-15s %6.2f %7.2f %7.2f %7.2f %9.1f %6s %018llx %d\n", renderLayerName(layer), blocks.ms / k,
                render / k, encode / k, (blocks.ms + render + encode) / k, bytes / k / 1024, typeList.c_str(),
                static_cast<unsigned long long>(digest), wrong);
    if (layer == RenderLayer::Elevation || layer == RenderLayer::Slope) {
      all += blocks.ms + render + encode;
      allTiles += static_cast<int>(windows.size());
    }
  }
  std::printf("elevation + slope (what tile_latency.py asks): %.2f ms a tile\n", all / allTiles);
  forgetStoredRasters(work.string());
  fs::remove_all(work);
  return 0;
}
