#include "maps/dem_pyramid.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <sys/stat.h>

#include <cerrno>
#include <cinttypes>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <list>
#include <mutex>
#include <string>
#include <stdexcept>
#include <vector>

#include "core/terrain/layers.hpp"
#include "maps/average_levels.hpp"
#include "maps/block_cache.hpp"
#include "maps/dem_error.hpp"
#include "maps/grid_file.hpp"
#include "maps/gdal_env.hpp"
#include "maps/tile_grid.hpp"

namespace rover::maps {

namespace {

namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

int ceilDiv(int a, int b) { return static_cast<int>((static_cast<long long>(a) + b - 1) / b); }

std::string fileName(const std::string& path) { return fs::path(path).filename().string(); }

// A failed write into the data dir: DiskFull when the disk is to blame, else the server's fault
// (std::runtime_error, its path stays in the server's log).
[[noreturn]] void failWrite(const std::string& path, const std::string& tmp, int err, double bytes) {
  const std::string gdal = CPLGetLastErrorMsg();
  std::error_code ec;
  for (const std::string& f : {tmp, tmp + ".aux.xml", tmp + ".ovr.tmp"}) fs::remove(f, ec);
  if (lacksSpace(path, err, bytes)) throw DiskFull(fileName(path));
  throw std::runtime_error("cannot write " + path + (gdal.empty() ? "" : " (" + gdal + ")"));
}

void moveIntoPlace(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot move " + tmp + " into place: " + ec.message());
}

// The geotransform and CRS a stored raster carries (writeGeoTiff's convention for a grid
// without georeferencing: 1 cell = its size in metres, origin at the lower-left corner).
void georeference(GDALDatasetH ds, const GridGeometry& g, const GeoReference& geo) {
  double gt[6] = {0, g.cellWidth, 0, g.rows * g.cellHeight, 0, -g.cellHeight};
  if (geo.valid) std::copy(geo.geotransform.begin(), geo.geotransform.end(), gt);
  GDALSetGeoTransform(ds, gt);
  if (!geo.crsWkt.empty()) GDALSetProjection(ds, geo.crsWkt.c_str());
}

// One overview per zoom below the native one (none for a map of one tile).
int overviewLevels(const GridGeometry& g) { return tileGridOf(g.rows, g.cols).nativeZoom; }

Dataset openStored(const std::string& path) {
  ensureGdal();
  Dataset ds(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds || GDALGetRasterCount(ds.get()) < 1) throw std::runtime_error("cannot read the stored raster " + path);
  return ds;
}

// Open handles of stored rasters, reused from tile to tile (issue 24: cold tiles). Opening dem.tif
// (its header, six directories, the CRS, GDAL's probes for sidecar files) was 7 % of the server's
// CPU in openat alone while serving cold tiles, and a fresh handle has none of the blocks a
// neighbouring tile just decompressed (GDAL's block cache keeps a dataset's blocks while it is
// open, within GDAL_CACHEMAX). A handle serves one thread at a time. A file is known by its path,
// device, inode, size and modification time, so a path rewritten in place (a test's scratch file)
// never reads through an old handle. At most kIdlePerFile idle handles per file and kFiles files
// are kept, least recently used closed first; forgetStoredRasters drops a deleted map's.
class OpenRasters {
 public:
  static OpenRasters& instance() {
    static OpenRasters o;
    return o;
  }

  // A handle on `path`: an idle one of the same file, or a new one (throws std::runtime_error).
  Dataset take(const std::string& path, struct stat& id) {
    if (::stat(path.c_str(), &id) != 0) throw std::runtime_error("cannot read the stored raster " + path);
    std::vector<Dataset> stale;  // closed outside the lock
    {
      std::lock_guard lock(mutex_);
      for (auto it = files_.begin(); it != files_.end(); ++it) {
        if (it->path != path) continue;
        if (!same(it->id, id)) {
          stale = std::move(it->idle);
          files_.erase(it);
          break;
        }
        files_.splice(files_.begin(), files_, it);
        if (!it->idle.empty()) {
          Dataset ds = std::move(it->idle.back());
          it->idle.pop_back();
          return ds;
        }
        break;
      }
    }
    return openStored(path);
  }

  // `ds`, which read `path` as `id` without an error, back to the idle handles.
  void give(const std::string& path, const struct stat& id, Dataset ds) {
    std::vector<Dataset> closed;
    {
      std::lock_guard lock(mutex_);
      auto it = std::find_if(files_.begin(), files_.end(), [&](const File& f) { return f.path == path; });
      if (it == files_.end()) {
        files_.push_front(File{path, id, {}});
        it = files_.begin();
      }
      if (same(it->id, id) && it->idle.size() < kIdlePerFile) it->idle.push_back(std::move(ds));
      else closed.push_back(std::move(ds));
      while (files_.size() > kFiles) {
        for (auto& d : files_.back().idle) closed.push_back(std::move(d));
        files_.pop_back();
      }
    }
  }

  void forget(const std::string& prefix) {
    std::vector<Dataset> closed;
    std::lock_guard lock(mutex_);
    for (auto it = files_.begin(); it != files_.end();) {
      if (it->path.rfind(prefix, 0) == 0) {
        for (auto& d : it->idle) closed.push_back(std::move(d));
        it = files_.erase(it);
      } else {
        ++it;
      }
    }
  }

 private:
  static constexpr std::size_t kIdlePerFile = 4, kFiles = 32;
  struct File {
    std::string path;
    struct stat id;
    std::vector<Dataset> idle;
  };
  static bool same(const struct stat& a, const struct stat& b) {
    return a.st_dev == b.st_dev && a.st_ino == b.st_ino && a.st_size == b.st_size &&
           a.st_mtim.tv_sec == b.st_mtim.tv_sec && a.st_mtim.tv_nsec == b.st_mtim.tv_nsec;
  }
  std::mutex mutex_;
  std::list<File> files_;  // most recently used first
};

// A stored raster's handle on loan: given back by keep() after a read without error, closed
// otherwise (a handle that failed once is not trusted again).
class StoredLease {
 public:
  explicit StoredLease(std::string path) : path_(std::move(path)), ds_(OpenRasters::instance().take(path_, id_)) {
    // A VRT opens its overviews' files when first asked for them: all of them now, while its
    // grid is open, so that a COG replacing the raw files (which are then removed) cannot leave
    // this read without its levels, falling back to the full-size cells unnoticed. A level gone
    // already is an error (the caller reads dem.tif instead: server/api/map_files.hpp).
    if (isVrt()) {
      GDALRasterBandH band = GDALGetRasterBand(ds_.get(), 1);
      for (int i = 0; band && i < GDALGetOverviewCount(band); ++i)
        if (!GDALGetOverview(band, i)) throw std::runtime_error("an overview level of " + path_ + " does not open");
    }
  }
  GDALDatasetH get() const { return ds_.get(); }
  const std::string& path() const { return path_; }
  const struct stat& id() const { return id_; }
  // A raw DEM's VRT (writeRawDem) is never kept: it lives until its COG replaces it, and an idle
  // handle would hold its removed files' disk space; opening it parses a few lines of XML.
  void keep() {
    if (!isVrt()) OpenRasters::instance().give(path_, id_, std::move(ds_));
  }

 private:
  bool isVrt() const { return path_.size() >= 4 && path_.compare(path_.size() - 4, 4, ".vrt") == 0; }
  std::string path_;
  struct stat id_ {};
  Dataset ds_;
};

// The band whose cells are the blocks of `step`: band 1 itself, or its overview of that factor;
// null when the file has no such level (a map stored before the pyramid). The tile grid's blocks
// are ceil(size / step) along a side; GDAL's COG driver sizes its overviews by halving the level
// above, rounding down (530 → 265 → 132), so a level may lack the last, cut block (readLevel).
GDALRasterBandH levelBand(GDALDatasetH ds, int step) {
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  if (step == 1) return band;
  const int w = ceilDiv(GDALGetRasterXSize(ds), step), h = ceilDiv(GDALGetRasterYSize(ds), step);
  for (int i = 0; i < GDALGetOverviewCount(band); ++i) {
    GDALRasterBandH o = GDALGetOverview(band, i);
    if (!o) continue;
    const int ow = GDALGetRasterBandXSize(o), oh = GDALGetRasterBandYSize(o);
    if ((ow == w || ow == w - 1) && (oh == h || oh == h - 1) && ow > 0 && oh > 0) return o;
  }
  return nullptr;
}

void readWindow(GDALRasterBandH band, int c0, int r0, int cols, int rows, void* out, GDALDataType type,
                const std::string& path) {
  CPLErrorReset();
  if (GDALRasterIO(band, GF_Read, c0, r0, cols, rows, out, cols, rows, type, 0, 0) != CE_None)
    throw std::runtime_error("cannot read a window of the stored raster " + path + " (" + CPLGetLastErrorMsg() + ")");
}

// A window of a level of `ds`'s file: through the decoded blocks its handles share
// (maps/block_cache.hpp), or GDAL's own reading where that cache does not apply.
void readLevelWindow(const StoredLease& ds, GDALRasterBandH level, int c0, int r0, int cols, int rows, void* out,
                     GDALDataType type) {
  if (!readThroughBlocks(ds.get(), level, ds.path(), ds.id(), c0, r0, cols, rows, out, type))
    readWindow(level, c0, r0, cols, rows, out, type, ds.path());
}

// `span`'s blocks from `level` of `ds`: a block past the level's last row or column (the cut
// block a rounded-down overview lacks) takes its nearest neighbour's value.
template <class T>
void readLevel(const StoredLease& ds, GDALRasterBandH level, const BlockSpan& s, T* out, GDALDataType type) {
  const int rows = GDALGetRasterBandYSize(level), cols = GDALGetRasterBandXSize(level);
  if (s.r0 + s.rows <= rows && s.c0 + s.cols <= cols) {
    readLevelWindow(ds, level, s.c0, s.r0, s.cols, s.rows, out, type);
    return;
  }
  const int r0 = std::min(s.r0, rows - 1), r1 = std::min(s.r0 + s.rows, rows);
  const int c0 = std::min(s.c0, cols - 1), c1 = std::min(s.c0 + s.cols, cols);
  std::vector<T> got(std::size_t(r1 - r0) * (c1 - c0));
  readLevelWindow(ds, level, c0, r0, c1 - c0, r1 - r0, got.data(), type);
  for (int i = 0; i < s.rows; ++i) {
    const int r = std::min(s.r0 + i, rows - 1) - r0;
    for (int j = 0; j < s.cols; ++j)
      out[std::size_t(i) * s.cols + j] = got[std::size_t(r) * (c1 - c0) + (std::min(s.c0 + j, cols - 1) - c0)];
  }
}

// The cells of `span`'s blocks at full resolution (clipped to the raster): what a level the file
// lacks is computed from.
BlockSpan cellsOf(const BlockSpan& s, int step, int rows, int cols) {
  const int r0 = s.r0 * step, c0 = s.c0 * step;
  return {r0, c0, std::min(rows, (s.r0 + s.rows) * step) - r0, std::min(cols, (s.c0 + s.cols) * step) - c0};
}

}  // namespace

namespace {

// Writes the COG of `src` (band 1: the heights, NaN as nodata) at `path`.
// `geo` null: `src` carries its georeferencing and nodata already (a raw DEM's VRT). `cancelled`,
// polled as the driver goes, ends the write early (nothing left behind, std::runtime_error).
void writeCog(const std::string& path, GDALDatasetH src, const GridGeometry& g, const GeoReference* geo,
              const std::function<bool()>& cancelled = {}) {
  if (geo) {
    georeference(src, g, *geo);
    GDALSetRasterNoDataValue(GDALGetRasterBand(src, 1), std::numeric_limits<double>::quiet_NaN());
  }
  // 128² blocks, the COG driver's smallest: a tile reads its 256² cells and a one-cell halo, which
  // with 256² blocks aligned on the tile grid meant decoding 3 × 3 blocks (2.3 MiB) for one; with
  // 128² blocks 4 × 4 (1 MiB). Decoding was half a cold tile's CPU on a 7000² map (ZSTD and the
  // predictor: 3.9 unique blocks a tile over big_map.py's 128 cold tiles). With the shared decoded
  // blocks (maps/block_cache.hpp) 3.5-4.1 -> 2.3-2.7 ms of server CPU a cold tile (big_map.py,
  // alternating with the 256² build, load 6). The price is in the background compression: the
  // driver compresses each block as a job of its own, and four times as many took the 7000² map's
  // COG from 1.6-2.0 s to 2.2-2.9 s (gdal_translate: 5 % more CPU); the file was 1 % smaller.
  // ZSTD level 1 with horizontal differencing of the values' 32-bit patterns (PREDICTOR=2):
  // lossless, and read by every GDAL since 2.3. A cold tile decompresses up to 16 blocks (its halo
  // crosses block edges), and undoing the floating-point predictor (3) was 30 % of a cold tile's
  // CPU. Measured with gdal_translate -of COG on a 3000² generated DEM (big_map.py's terrain), one
  // thread, without overviews: ZSTD+2 writes in 0.17 s of CPU, reads back in 0.14 s, 27.7 MB;
  // ZSTD+3 0.32 s, 0.22 s, 22.5 MB; ZSTD alone 0.20 s, 0.13 s, 31.9 MB; LERC_ZSTD (lossless)
  // 0.63 s, 0.20 s, 31.9 MB. With overviews, DEFLATE level 1 + 3 (stored before) took 0.83 s to
  // write against ZSTD+3's 0.62 s, LZW + 3 0.96 s and 30 % more disk.
  const std::string count = "OVERVIEW_COUNT=" + std::to_string(overviewLevels(g));
  const char* options[] = {"BLOCKSIZE=128",        "COMPRESS=ZSTD",     "LEVEL=1",
                           "PREDICTOR=2",        "OVERVIEW_RESAMPLING=AVERAGE",
                           count.c_str(),          "NUM_THREADS=ALL_CPUS", "BIGTIFF=IF_SAFER",
                           overviewLevels(g) == 0 ? "OVERVIEWS=NONE" : "OVERVIEWS=AUTO", nullptr};
  const std::string tmp = path + ".tmp";
  CPLErrorReset();
  errno = 0;
  // The driver first writes the overviews to a temporary file next to `tmp` and copies them into
  // the COG. GDAL 3.6 compresses that file with ZSTD at libtiff's default level 9 (no option sets
  // its level), which was more than half of the write's CPU: on a 7000² DEM `gdal_translate -of
  // COG` with these options took 2.9 s of CPU, 1.3 s with the temporary file uncompressed, and the
  // COG is byte for byte the same. The price is disk while writing: 4·N/3 bytes instead of about
  // half that (COG_TMP_COMPRESSION is read on this thread, when the driver starts).
  const ThreadConfig uncompressedOverviews("COG_TMP_COMPRESSION", "NONE");
  GDALProgressFunc progress = nullptr;
  void* progressData = nullptr;
  if (cancelled) {
    progress = [](double, const char*, void* data) -> int { return !(*static_cast<const std::function<bool()>*>(data))(); };
    progressData = const_cast<std::function<bool()>*>(&cancelled);
  }
  Dataset out(GDALCreateCopy(GDALGetDriverByName("COG"), tmp.c_str(), src, FALSE,
                             const_cast<char**>(options), progress, progressData));
  const int err = errno;
  const bool failed = !out || CPLGetLastErrorType() >= CE_Failure;
  out.reset();  // flushes and closes
  if (failed || CPLGetLastErrorType() >= CE_Failure)
    failWrite(path, tmp, err ? err : errno, static_cast<double>(g.cellCount()) * 4.0 * 4.0 / 3.0);
  moveIntoPlace(tmp, path);
}

// The cells of `r` as they are, through a MEM band over the raster's own memory: no second copy.
Dataset memoryDataset(const Raster<float>& r, const std::string& path) {
  const GridGeometry& g = r.geometry;
  Dataset src(GDALCreate(GDALGetDriverByName("MEM"), "", g.cols, g.rows, 0, GDT_Float32, nullptr));
  if (!src) throw std::runtime_error("cannot make the in-memory dataset for " + path);
  char pointer[64];
  std::snprintf(pointer, sizeof pointer, "DATAPOINTER=%p", static_cast<const void*>(r.values.data()));
  const char* bandOptions[] = {pointer, nullptr};
  if (GDALAddBand(src.get(), GDT_Float32, const_cast<char**>(bandOptions)) != CE_None)
    throw std::runtime_error("cannot wrap the grid for " + path);
  return src;
}

// The metadata item of a mass COG that holds its ramp's top (GDAL keeps it in the TIFF's
// GDAL_METADATA tag).
constexpr const char* kRampTopItem = "ROVERPLAN_RAMP_TOP";

}  // namespace

void writeDemCog(const std::string& path, const Raster<float>& dem) {
  ensureGdal();
  GdalErrorLog errors;
  Dataset src = memoryDataset(dem, path);
  writeCog(path, src.get(), dem.geometry, &dem.geo);
}

void writeMassCog(const std::string& path, const Raster<float>& mass, const ColourRange& range) {
  ensureGdal();
  GdalErrorLog errors;
  Dataset src = memoryDataset(mass, path);
  char top[40];
  std::snprintf(top, sizeof top, "%.17g", range.hi);  // round-trips the double exactly
  GDALSetMetadataItem(src.get(), kRampTopItem, top, nullptr);
  writeCog(path, src.get(), mass.geometry, &mass.geo);
}

namespace {

std::string escapedXml(const std::string& text) {
  char* escaped = CPLEscapeString(text.c_str(), -1, CPLES_XML);
  std::string out(escaped);
  CPLFree(escaped);
  return out;
}

// A VRT of one float32 raw band over `file` (rows × cols, little-endian, maps/grid_file.hpp), its
// path relative to the VRT's folder, NaN as nodata; `inner` goes inside the band (overviews),
// `georef` inside the dataset.
std::string rawVrtXml(const std::string& file, int rows, int cols, const std::string& inner, const std::string& georef) {
  return "<VRTDataset rasterXSize=\"" + std::to_string(cols) + "\" rasterYSize=\"" + std::to_string(rows) + "\">" +
         georef +
         "<VRTRasterBand dataType=\"Float32\" band=\"1\" subClass=\"VRTRawRasterBand\">"
         "<NoDataValue>nan</NoDataValue><SourceFilename relativeToVRT=\"1\">" +
         escapedXml(file) + "</SourceFilename><ImageOffset>0</ImageOffset><PixelOffset>4</PixelOffset>"
         "<LineOffset>" + std::to_string(4ll * cols) + "</LineOffset><ByteOrder>LSB</ByteOrder>" + inner +
         "</VRTRasterBand></VRTDataset>";
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw GridFileError("cannot write " + path);
}

// The geotransform and CRS writeCog gives the COG (georeference), as VRT elements.
std::string georefXml(const GridGeometry& g, const GeoReference& geo) {
  double gt[6] = {0, g.cellWidth, 0, g.rows * g.cellHeight, 0, -g.cellHeight};
  if (geo.valid) std::copy(geo.geotransform.begin(), geo.geotransform.end(), gt);
  char text[200];
  std::snprintf(text, sizeof text, "<GeoTransform>%.17g, %.17g, %.17g, %.17g, %.17g, %.17g</GeoTransform>", gt[0],
                gt[1], gt[2], gt[3], gt[4], gt[5]);
  return (geo.crsWkt.empty() ? std::string() : "<SRS>" + escapedXml(geo.crsWkt) + "</SRS>") + text;
}

}  // namespace

std::vector<std::string> writeRawDem(const std::string& vrtPath, const std::string& gridFile, const GridGeometry& g,
                                     const GeoReference& geo) {
  ensureGdal();
  // The overview levels first, on every core (maps/average_levels.hpp: GDAL's AVERAGE with NaN as
  // nodata), as raw files next to the grid; memory: a band of rows per thread.
  //
  // Where every window is whole or no chunk of GDAL's cuts one (even shapes, small maps) the bytes
  // are GDAL's own. Where a level's size is odd on a large map they differ from GDAL's in the level
  // rows at the ends of GDAL's chunks of rows (8192 grid rows at 20000 columns): GDAL clips the
  // fractional window there and gives the clipped row a weight above 1, an artifact of its
  // chunking; ours are the whole windows, the same on every run and thread count. That is fine
  // because a map's levels never change after its import (maps are immutable; a new import gets
  // a new id, new tile ETags), so no tile of one map ever mixes the two; and the COG made later
  // (writeDemCogFromRaw) carries these very levels.
  const fs::path dir = fs::path(vrtPath).parent_path();
  const std::string stem = fs::path(vrtPath).stem().string();
  const std::vector<LevelFile> levels =
      writeAverageLevels(gridFile, g.rows, g.cols, overviewLevels(g), (dir / (stem + "-")).string());
  std::vector<std::string> files;
  struct RemoveOnThrow {
    std::vector<std::string>& files;
    const std::vector<LevelFile>& levels;
    bool done = false;
    ~RemoveOnThrow() {
      if (done) return;
      std::error_code ec;
      for (const LevelFile& l : levels) fs::remove(l.path, ec);
      for (const std::string& f : files) fs::remove(f, ec);
    }
  } removeOnThrow{files, levels};
  // Each level a raw band of its own VRT (GDAL's <Overview> names a dataset); every path relative
  // to its VRT, so the folder can move (staging -> the map's folder) and still read.
  std::string overviews;
  for (const LevelFile& l : levels) {
    const std::string vrt = l.path + ".vrt";
    writeText(vrt, rawVrtXml(fs::path(l.path).filename().string(), l.rows, l.cols, "", ""));
    files.push_back(l.path);
    files.push_back(vrt);
    overviews += "<Overview><SourceFilename relativeToVRT=\"1\">" + escapedXml(fs::path(vrt).filename().string()) +
                 "</SourceFilename><SourceBand>1</SourceBand></Overview>";
  }
  const std::string grid = fs::relative(gridFile, dir).string();
  writeText(vrtPath, rawVrtXml(grid, g.rows, g.cols, overviews, georefXml(g, geo)));
  files.push_back(vrtPath);
  removeOnThrow.done = true;
  return files;
}

void writeDemCogFromRaw(const std::string& path, const std::string& vrtPath, const std::function<bool()>& cancelled) {
  ensureGdal();
  GdalErrorLog errors;
  // The VRT carries the georeferencing and nodata writeCog would set: opened read-only, as is.
  Dataset src(GDALOpenEx(vrtPath.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!src) throw std::runtime_error("cannot open " + vrtPath + " (" + CPLGetLastErrorMsg() + ")");
  GridGeometry g;
  g.rows = GDALGetRasterYSize(src.get());
  g.cols = GDALGetRasterXSize(src.get());
  // Rows straight from the files into the driver's buffers (RawRasterBand's direct reads), not
  // through GDAL's block cache, which the rows read once would fill to its cap.
  const ThreadConfig directReads("GDAL_ONE_BIG_READ", "YES");
  writeCog(path, src.get(), g, nullptr, cancelled);
}

void writeDemCog(const std::string& path, const std::string& gridFile, const GridGeometry& g, const GeoReference& geo) {
  // The levels and their VRT next to the grid (4·N/3 bytes, removed before it returns); the COG
  // driver finds the levels as the source's overviews and only compresses them (OVERVIEWS=AUTO
  // uses a source's own) instead of computing them on one thread into its temporary file.
  const std::vector<std::string> files = writeRawDem(gridFile + "~raw.vrt", gridFile, g, geo);
  struct RemoveFiles {
    const std::vector<std::string>& files;
    ~RemoveFiles() {
      std::error_code ec;
      for (const std::string& f : files) fs::remove(f, ec);
    }
  } removeFiles{files};
  writeDemCogFromRaw(path, files.back());
}

void writeClassPyramid(const std::string& path, const Raster<std::uint8_t>& classes) {
  ensureGdal();
  GdalErrorLog errors;
  const GridGeometry& g = classes.geometry;
  // Blocks compressed on every core (the import waits for this file before it announces a map).
  const char* options[] = {"TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256", "COMPRESS=ZSTD", "ZSTD_LEVEL=1",
                           "BIGTIFF=IF_SAFER", "NUM_THREADS=ALL_CPUS", nullptr};
  const std::string tmp = path + ".tmp";
  CPLErrorReset();
  errno = 0;
  Dataset ds(GDALCreate(GDALGetDriverByName("GTiff"), tmp.c_str(), g.cols, g.rows, 1, GDT_Byte,
                        const_cast<char**>(options)));
  if (!ds) failWrite(path, tmp, errno, static_cast<double>(g.cellCount()));
  georeference(ds.get(), g, classes.geo);
  GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
  bool ok = GDALRasterIO(band, GF_Write, 0, 0, g.cols, g.rows, const_cast<std::uint8_t*>(classes.values.data()),
                         g.cols, g.rows, GDT_Byte, 0, 0) == CE_None;
  const int levels = overviewLevels(g);
  if (ok && levels > 0) {
    // Overviews allocated empty ("NONE"), then filled with the exact worst class of each block:
    // level k from level k − 1, 2 × 2 blocks at a time (blocks are aligned on the whole map).
    std::vector<int> factors;
    for (int k = 1; k <= levels; ++k) factors.push_back(1 << k);
    ok = GDALBuildOverviews(ds.get(), "NONE", levels, factors.data(), 0, nullptr, nullptr, nullptr) == CE_None;
    Raster<std::uint8_t> level;
    const Raster<std::uint8_t>* finer = &classes;
    for (int k = 0; ok && k < levels; ++k) {
      const GridGeometry& f = finer->geometry;
      Raster<std::uint8_t> next = blockWorstClass(*finer, 2, BlockSpan{0, 0, ceilDiv(f.rows, 2), ceilDiv(f.cols, 2)});
      GDALRasterBandH o = GDALGetOverview(band, k);
      ok = o && GDALGetRasterBandXSize(o) == next.geometry.cols && GDALGetRasterBandYSize(o) == next.geometry.rows &&
           GDALRasterIO(o, GF_Write, 0, 0, next.geometry.cols, next.geometry.rows, next.values.data(),
                        next.geometry.cols, next.geometry.rows, GDT_Byte, 0, 0) == CE_None;
      level = std::move(next);
      finer = &level;
    }
  }
  const int err = errno;
  ds.reset();
  if (!ok || CPLGetLastErrorType() >= CE_Failure) failWrite(path, tmp, err ? err : errno, static_cast<double>(g.cellCount()));
  moveIntoPlace(tmp, path);
}

terrain::Dem readDemBlocks(const std::string& path, const DemHeader& header, int step, const BlockSpan& s) {
  GdalErrorLog errors;
  StoredLease ds(path);
  const GridGeometry& g = header.geometry;
  GDALRasterBandH base = GDALGetRasterBand(ds.get(), 1);
  int hasNodata = 0;
  const float nodata = static_cast<float>(GDALGetRasterNoDataValue(base, &hasNodata));
  auto toNaN = [&](Raster<float>& r) {
    if (!hasNodata || std::isnan(nodata)) return;  // NaN cells are NaN already
    float* v = r.values.data();
    for (std::size_t i = 0, n = std::size_t(r.values.size()); i < n; ++i)
      if (v[i] == nodata) v[i] = kNaN;
  };
  terrain::Dem out;
  out.rowCellWidth = blockRowWidths(header.rowCellWidth, g.rows, step, s);
  if (GDALRasterBandH level = levelBand(ds.get(), step)) {
    out.z = Raster<float>(GridGeometry{s.rows, s.cols, g.cellWidth * step, g.cellHeight * step}, kNaN);
    readLevel(ds, level, s, out.z.values.data(), GDT_Float32);
    toNaN(out.z);
  } else {
    const BlockSpan c = cellsOf(s, step, g.rows, g.cols);
    Raster<float> cells(GridGeometry{c.rows, c.cols, g.cellWidth, g.cellHeight}, kNaN);
    readWindow(base, c.c0, c.r0, c.cols, c.rows, cells.values.data(), GDT_Float32, path);
    toNaN(cells);
    out.z = blockMean(cells, step, BlockSpan{0, 0, s.rows, s.cols});
  }
  ds.keep();
  return out;
}

Raster<std::uint8_t> readClassBlocks(const std::string& path, int step, const BlockSpan& s) {
  GdalErrorLog errors;
  StoredLease ds(path);
  double gt[6] = {0, 1, 0, 0, 0, -1};
  GDALGetGeoTransform(ds.get(), gt);
  const int rows = GDALGetRasterYSize(ds.get()), cols = GDALGetRasterXSize(ds.get());
  if (GDALRasterBandH level = levelBand(ds.get(), step)) {
    Raster<std::uint8_t> out(GridGeometry{s.rows, s.cols, std::fabs(gt[1]) * step, std::fabs(gt[5]) * step}, 0);
    readLevel(ds, level, s, out.values.data(), GDT_Byte);
    ds.keep();
    return out;
  }
  const BlockSpan c = cellsOf(s, step, rows, cols);
  Raster<std::uint8_t> cells(GridGeometry{c.rows, c.cols, std::fabs(gt[1]), std::fabs(gt[5])}, 0);
  readWindow(GDALGetRasterBand(ds.get(), 1), c.c0, c.r0, c.cols, c.rows, cells.values.data(), GDT_Byte, path);
  ds.keep();
  return blockWorstClass(cells, step, BlockSpan{0, 0, s.rows, s.cols});
}

void forgetStoredRasters(const std::string& dir) {
  std::string prefix = dir;
  if (!prefix.empty() && prefix.back() != '/') prefix += '/';
  OpenRasters::instance().forget(prefix);
  forgetDecodedBlocks(prefix);
}

terrain::Dem PyramidBlocks::dem(int step, const BlockSpan& span) const {
  return readDemBlocks(dem_, *header_, step, span);
}

Raster<std::uint8_t> PyramidBlocks::classes(int step, const BlockSpan& span) const {
  return readClassBlocks(classes_, step, span);
}

Raster<float> PyramidBlocks::pdm(int, const BlockSpan&) const {
  throw Error(ErrorCode::InvalidInput, "layer", "a stored map's pyramid holds no PDM");
}

MassPyramidBlocks::MassPyramidBlocks(std::string path, const GridGeometry& geometry) : path_(std::move(path)) {
  header_.geometry = geometry;
  GdalErrorLog errors;
  StoredLease ds(path_);
  const char* top = GDALGetMetadataItem(ds.get(), kRampTopItem, nullptr);
  char* end = nullptr;
  const double hi = top ? std::strtod(top, &end) : 0;
  if (!top || end == top || !(hi > 0))
    throw std::runtime_error("the stored PDM mass " + path_ + " carries no colour ramp");
  if (GDALGetRasterXSize(ds.get()) != geometry.cols || GDALGetRasterYSize(ds.get()) != geometry.rows)
    throw std::runtime_error("the stored PDM mass " + path_ + " is not on its map's grid");
  range_ = {0, hi};
  ds.keep();
}

terrain::Dem MassPyramidBlocks::dem(int, const BlockSpan&) const {
  throw Error(ErrorCode::InvalidInput, "layer", "a PDM's pyramid holds no DEM");
}

Raster<std::uint8_t> MassPyramidBlocks::classes(int, const BlockSpan&) const {
  throw Error(ErrorCode::InvalidInput, "layer", "a PDM's pyramid holds no classes");
}

Raster<float> MassPyramidBlocks::pdm(int step, const BlockSpan& span) const {
  return readDemBlocks(path_, header_, step, span).z;
}

PyramidInfo pyramidInfo(const std::string& path) {
  GdalErrorLog errors;
  Dataset ds = openStored(path);
  PyramidInfo p;
  p.rows = GDALGetRasterYSize(ds.get());
  p.cols = GDALGetRasterXSize(ds.get());
  GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
  GDALGetBlockSize(band, &p.blockWidth, &p.blockHeight);
  for (int i = 0; i < GDALGetOverviewCount(band); ++i) {
    GDALRasterBandH o = GDALGetOverview(band, i);
    p.overviews.emplace_back(GDALGetRasterBandXSize(o), GDALGetRasterBandYSize(o));
  }
  if (const char* c = GDALGetMetadataItem(ds.get(), "COMPRESSION", "IMAGE_STRUCTURE")) p.compression = c;
  if (const char* l = GDALGetMetadataItem(ds.get(), "LAYOUT", "IMAGE_STRUCTURE")) p.layout = l;
  return p;
}

}  // namespace rover::maps
