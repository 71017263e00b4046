#include "maps/dem_io.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>
#include <gdal_priv.h>
#include <gdal_utils.h>
#include <ogr_srs_api.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <optional>
#include <filesystem>
#include <functional>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/common/error.hpp"
#include "core/common/parallel.hpp"
#include "core/terrain/layers.hpp"
#include "maps/cell_metres.hpp"
#include "maps/dem_error.hpp"
#include "maps/dem_grid_plan.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::maps {

namespace {

std::string gdalMessage() {
  std::string m = CPLGetLastErrorMsg();
  return m.empty() ? "" : " (" + m + ")";
}

std::string lowerExt(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

bool isTiff(const std::string& head) {
  return head.rfind(std::string("II*\0", 4), 0) == 0 || head.rfind(std::string("MM\0*", 4), 0) == 0 ||
         head.rfind(std::string("II+\0", 4), 0) == 0 || head.rfind(std::string("MM\0+", 4), 0) == 0;
}

// Why a file did not open, in words: the label a PDS3 .IMG needs, a damaged GeoTIFF, or a format
// we do not read.
std::string unreadableReason(const std::string& path, bool upload) {
  const std::string head = firstBytes(path, 64);
  if (isTiff(head)) return "truncated or corrupt GeoTIFF";
  const bool attachedLabel = head.find("PDS_VERSION_ID") != std::string::npos ||
                             head.find("ODL_VERSION_ID") != std::string::npos;
  if (lowerExt(path) == ".img" && !attachedLabel)
    return "the label is missing: a PDS3 .IMG needs its .LBL (an ENVI .img its .hdr) — upload both "
           "files together, or a zip holding both";
  if (attachedLabel) return "truncated or corrupt PDS3 product (its label or image does not read)";
  if (upload) return "not a raster format roverplan reads (accepted: " + uploadFormatsInWords() + ")";
  return "not a raster GDAL can read" + gdalMessage();
}

// "1199 bytes", "17 KB", "98 MB": a file size for a message.
std::string sizeInWords(double bytes) {
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB"};
  int u = 0;
  if (bytes >= 10000)
    while (bytes >= 1000 && u < 4) bytes /= 1000, ++u;
  std::ostringstream s;
  s << std::llround(bytes) << " " << units[u];
  return s.str();
}

// A raw (uncompressed) raster reads cells past the end of its data file as 0: a 17 KB .bin whose
// .hdr says 7000 x 7000 would become a 49 M-cell map of zeros. Refuse unless the data file holds
// header offset + every cell (GDAL's raw binary layout: ENVI, EHdr, PDS, ISIS2/3, VICAR, PDS4,
// uncompressed GeoTIFF). Surfer binary grids have no such layout: their one file must at least
// hold every cell.
void checkRawDataSize(GDALDatasetH ds, const std::string& driver, const std::string& shownPath,
                      const std::function<std::string(const std::string&)>& shown) {
  const int rows = GDALGetRasterYSize(ds), cols = GDALGetRasterXSize(ds), bands = GDALGetRasterCount(ds);
  auto sizeOf = [](const std::string& f) -> double {
    VSIStatBufL st;
    return VSIStatL(f.c_str(), &st) == 0 ? static_cast<double>(st.st_size) : 0.0;
  };
  char** files = GDALGetFileList(ds);
  std::vector<std::string> list;
  for (char** f = files; f && *f; ++f) list.emplace_back(*f);
  CSLDestroy(files);
  std::string dataFile, header;
  double needed = 0, offset = 0;
  GDALDataset::RawBinaryLayout layout;
  // EHdr leaves the layout's file name empty: its data file is the one opened (the .bil).
  if (GDALDataset::FromHandle(ds)->GetRawBinaryLayout(layout) && layout.osRawFilename.empty() && driver == "EHdr")
    layout.osRawFilename = GDALGetDescription(ds);
  if (!layout.osRawFilename.empty()) {
    const double sample = GDALGetDataTypeSizeBytes(layout.eDataType);
    auto span = [](double n, double stride) { return n > 1 ? std::max(0.0, (n - 1) * stride) : 0.0; };
    offset = static_cast<double>(layout.nImageOffset);
    needed = offset + span(rows, static_cast<double>(layout.nLineOffset)) +
             span(cols, static_cast<double>(layout.nPixelOffset)) +
             span(bands, static_cast<double>(layout.nBandOffset)) + sample;
    dataFile = layout.osRawFilename;
  } else if ((driver == "GSBG" || driver == "GS7BG") && !list.empty()) {
    needed = static_cast<double>(rows) * cols * bands *
             GDALGetDataTypeSizeBytes(GDALGetRasterDataType(GDALGetRasterBand(ds, 1)));
    dataFile = list.front();
  } else {
    return;
  }
  const double held = sizeOf(dataFile);
  if (held >= needed) return;
  // The header is the file that described the raster: another file of the set, else the file itself.
  header = dataFile;
  for (const auto& f : list)
    if (f != dataFile) {
      header = f;
      break;
    }
  const std::string headerName = std::filesystem::path(shown(header)).filename().string();
  const std::string dataName = std::filesystem::path(shown(dataFile)).filename().string();
  failFile(shownPath, headerName + " describes " + std::to_string(rows) + " × " + std::to_string(cols) + " cells" +
                      (bands > 1 ? " in " + std::to_string(bands) + " bands" : "") +
                      (offset > 0 ? " after a header offset of " + exactNumber(offset) + " bytes" : "") + " but " + dataName +
                      " holds only " + sizeInWords(held) + ": truncated or mismatched");
}

// A block GDAL must hold to read band 1, bounded before any read. A 674-byte GeoTIFF may declare
// 16384 × 16384 sparse tiles of 64 pixel-interleaved Float64 bands: reading one pixel then makes
// GDAL calloc the whole 137 GB block (found by fuzz_dem_ingest). A block is refused when it is
// over 512 MiB, or over 16 MiB and over four times the whole raster (no real product tiles a
// raster with blocks much larger than itself).
void checkBlockSize(GDALDatasetH ds, const std::string& shownPath) {
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  int bx = 0, by = 0;
  GDALGetBlockSize(band, &bx, &by);
  const double bands = GDALGetRasterCount(ds);
  const double sample = GDALGetDataTypeSizeBytes(GDALGetRasterDataType(band));
  const char* interleave = GDALGetMetadataItem(ds, "INTERLEAVE", "IMAGE_STRUCTURE");
  const bool pixelInterleaved = interleave && std::string(interleave) == "PIXEL";
  const double block = static_cast<double>(bx) * by * sample * (pixelInterleaved ? bands : 1.0);
  const double raster =
      static_cast<double>(GDALGetRasterXSize(ds)) * GDALGetRasterYSize(ds) * sample * bands;
  constexpr double kMiB = 1024.0 * 1024.0;
  if (block > 512 * kMiB || (block > 16 * kMiB && block > 4 * raster))
    failFile(shownPath, "its blocks of " + std::to_string(bx) + " × " + std::to_string(by) + " cells" +
                        (pixelInterleaved && bands > 1
                             ? " × " + std::to_string(static_cast<long long>(bands)) + " bands"
                             : "") +
                        " (" + sizeInWords(block) + " each) are too large to read for a raster of " +
                        sizeInWords(raster) + "; re-tile it (gdal_translate -co TILED=YES)");
}

// Whether a failed GeoTIFF write was the disk's fault. libtiff often names only the symptom
// ("TIFFWriteDirectoryTagData:IO error writing tag data", sometimes "_tiffWriteProc:No space left
// on device") and errno may be overwritten by the time the file is closed, so a folder with less
// free space than the uncompressed raster (`bytes`) plus 64 KiB counts as full too.
}  // namespace

bool lacksSpace(const std::string& path, int err, double bytes) {
  if (err == ENOSPC || err == EDQUOT || err == EFBIG) return true;
  const std::string msg = CPLGetLastErrorMsg();
  if (msg.find("No space left") != std::string::npos || msg.find("quota exceeded") != std::string::npos ||
      msg.find("File too large") != std::string::npos)
    return true;
  struct statvfs fs {};
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  if (statvfs(dir.c_str(), &fs) != 0) return false;
  return static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize) < bytes + 65536.0;
}

namespace {

// Runs GDAL's warper into a lazy in-memory VRT: nothing is read until RasterIO, so the size can be
// checked against the budget first.
// `detail` adds GDAL's own message (the command line's files are the user's own; an upload's
// messages never show GDAL internals).
Dataset warpToVrt(GDALDatasetH src, const std::vector<std::string>& args, const std::string& path, bool detail) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  GDALWarpAppOptions* opts = GDALWarpAppOptionsNew(argv.data(), nullptr);
  if (!opts) failFile(path, "invalid warp options" + (detail ? gdalMessage() : ""));
  int usageError = 0;
  CPLErrorReset();
  GDALDatasetH out = GDALWarp("", nullptr, 1, &src, opts, &usageError);
  GDALWarpAppOptionsFree(opts);
  if (!out) failFile(path, "cannot crop/resample" + (detail ? gdalMessage() : ""));
  return Dataset(out);
}

// Refuses options no file can meet, before the file is opened.
void checkOptions(const LoadOptions& opt, const std::string& shown) {
  if (!(opt.verticalScale != 0) || !std::isfinite(opt.verticalScale))
    failFile(shown, "vertical scale must be a finite non-zero number", "vertical_scale");
  if (!std::isfinite(opt.verticalOffset) || std::fabs(opt.verticalOffset) > 1e8)
    failFile(shown, "vertical offset must be a finite number of metres within ±1e8", "vertical_offset");
  if (opt.cellSize < 0 || !std::isfinite(opt.cellSize))
    failFile(shown, "cell size must be a positive number of metres", "cell");
  const std::vector<std::string> algs{"auto", "near", "average", "bilinear", "cubic"};
  if (std::find(algs.begin(), algs.end(), opt.resampling) == algs.end())
    failFile(shown, "resampling must be auto, near, average, bilinear or cubic", "resampling");
}

// Opens the file (an upload through its sandbox; a PDS3 .IMG through its label) and refuses what
// cannot be read safely: no raster band, a raw data file shorter than its header says, a block
// larger than any real product's.
Dataset openSource(const std::string& path, const UploadSandbox* sandbox, const std::string& shown) {
  VSIStatBufL st;
  if (VSIStatL(path.c_str(), &st) != 0) failFile(shown, "no such file");
  if (!VSI_ISDIR(st.st_mode) && st.st_size == 0) failFile(shown, "empty file");
  std::string refusal;
  auto open = [&](const std::string& p) {
    CPLErrorReset();
    if (sandbox) return openUpload(p, *sandbox, refusal);
    return Dataset(GDALOpenEx(p.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  };
  Dataset src = open(path);
  if (!src && refusal.empty() && lowerExt(path) == ".img") {
    // A PDS3 product with a detached label: users often pick the .IMG; GDAL opens the .LBL.
    for (const char* lbl : {".LBL", ".lbl"}) {
      const std::string label = std::filesystem::path(path).replace_extension(lbl).string();
      if (VSIStatL(label.c_str(), &st) == 0) {
        src = open(label);
        if (src || !refusal.empty()) break;
      }
    }
  }
  if (!refusal.empty()) throw Error(ErrorCode::InvalidInput, "file", refusal);  // names the file itself
  if (!src) failFile(shown, unreadableReason(path, sandbox != nullptr));
  if (GDALGetRasterCount(src.get()) < 1) failFile(shown, "the file holds no raster band");
  checkRawDataSize(src.get(), GDALGetDriverShortName(GDALGetDatasetDriver(src.get())), shown,
                   [&](const std::string& f) { return sandbox ? sandbox->uploadName(f) : f; });
  checkBlockSize(src.get(), shown);
  return src;
}

// What the file's header says: driver, size, band 1's nodata, scale and offset, CRS.
void describeSource(GDALDatasetH src, DemInfo& info) {
  info.driver = GDALGetDriverShortName(GDALGetDatasetDriver(src));
  info.sourceCols = GDALGetRasterXSize(src);
  info.sourceRows = GDALGetRasterYSize(src);
  GDALRasterBandH band = GDALGetRasterBand(src, 1);
  int has = 0;
  double nodata = GDALGetRasterNoDataValue(band, &has);
  if (has) info.nodata = nodata;
  double scale = GDALGetRasterScale(band, &has);
  info.scale = has && scale != 0 ? scale : 1.0;
  double offset = GDALGetRasterOffset(band, &has);
  info.offset = has ? offset : 0.0;
  if (OGRSpatialReferenceH srs = GDALGetSpatialRef(src)) {
    info.crsName = OSRGetName(srs) ? OSRGetName(srs) : "";
    info.geographic = OSRIsGeographic(srs);
  }
}

// The file's georeferencing is the client's word: checked before any of it is used (issue 22).
void checkGeotransform(const std::array<double, 6>& gt, int rows, int cols, OGRSpatialReferenceH crs,
                       const std::string& shown) {
  if (auto p = georefProblem(gt, rows, cols, crsUnits(crs))) failFile(shown, p->reason, p->field);
}

// Band 1 of `grid` into `z` (sized to the grid), in metres: the file's scale and offset and the
// vertical scale applied, nodata (the file's value where the grid was not warped) made NaN.
// `col0`, `row0`: the window's first cell (a mission area's window, loadDemWindow).
void readHeights(GDALDatasetH grid, bool compareNodata, const LoadOptions& opt, Raster<float>& heights,
                 DemInfo& info, const std::string& shown, int col0 = 0, int row0 = 0) {
  const int cols = heights.geometry.cols, rows = heights.geometry.rows;
  CPLErrorReset();
  if (GDALRasterIO(GDALGetRasterBand(grid, 1), GF_Read, col0, row0, cols, rows, heights.values.data(), cols,
                   rows, GDT_Float32, 0, 0) != CE_None)
    failFile(shown, "truncated or corrupt " + formatInWords(info.driver) + " (its data does not read)" +
                        (opt.upload ? "" : gdalMessage()));
  const float nodataF = info.nodata ? static_cast<float>(*info.nodata) : 0.0f;
  const double k = info.scale * opt.verticalScale, o = info.offset * opt.verticalScale + opt.verticalOffset;
  float* z = heights.values.data();
  // In bands of rows on every core (issue 24: on a 300 M-cell upload this pass ran on one core
  // while the other, done decoding, stood idle): each band's figures are its own slot, so the
  // result does not depend on the thread count; an infinity anywhere fails the file.
  struct Figures {
    double lo = INFINITY, hi = -INFINITY;
    std::int64_t nodata = 0;
    bool infinite = false;
  };
  constexpr std::int64_t kBandCells = 1 << 22;
  const std::int64_t cells = static_cast<std::int64_t>(rows) * cols;
  std::vector<Figures> bands(static_cast<std::size_t>((cells + kBandCells - 1) / kBandCells));
  parallelFor(bands.size(), cells > kBandCells ? std::clamp(std::thread::hardware_concurrency(), 1u, 4u) : 1u,
              [&](std::size_t b) {
                Figures& f = bands[b];
                const std::int64_t end = std::min(cells, static_cast<std::int64_t>(b + 1) * kBandCells);
                for (std::int64_t i = static_cast<std::int64_t>(b) * kBandCells; i < end; ++i) {
                  const float v = z[i];
                  if (std::isnan(v) || (compareNodata && v == nodataF)) {
                    z[i] = NAN;
                    ++f.nodata;
                    continue;
                  }
                  if (std::isinf(v)) {
                    f.infinite = true;
                    return;
                  }
                  const double h = v * k + o;
                  z[i] = static_cast<float>(h);
                  f.lo = std::min(f.lo, h);
                  f.hi = std::max(f.hi, h);
                }
              });
  double lo = INFINITY, hi = -INFINITY;
  for (const Figures& f : bands) {
    if (f.infinite) failFile(shown, "the raster holds infinite values");
    info.nodataCells += f.nodata;
    lo = std::min(lo, f.lo);
    hi = std::max(hi, f.hi);
  }
  if (info.nodataCells == static_cast<std::int64_t>(rows) * cols) failFile(shown, "every cell is nodata");
  info.minHeight = lo;
  info.maxHeight = hi;
}

// The north-up grid of a file read as it is (a stored map, a CLI user's DEM for a mission
// area): its header, checked, and its cells' size in metres for every row.
struct NativeGrid {
  Dataset src;
  DemInfo info;
  std::array<double, 6> gt{};
  OGRSpatialReferenceH srs = nullptr;
  CellMetres metres;
};

NativeGrid openNative(const std::string& path) {
  NativeGrid n;
  n.src = openSource(path, nullptr, path);
  n.info.path = path;
  describeSource(n.src.get(), n.info);
  n.srs = GDALGetSpatialRef(n.src.get());
  n.info.georeferenced = GDALGetGeoTransform(n.src.get(), n.gt.data()) == CE_None;
  if (n.info.georeferenced) checkGeotransform(n.gt, n.info.sourceRows, n.info.sourceCols, n.srs, path);
  else n.gt = {0, 1, 0, static_cast<double>(n.info.sourceRows), 0, -1};
  if (n.gt[2] != 0 || n.gt[4] != 0 || n.gt[5] > 0)
    failFile(path, "a mission area needs a north-up raster (this one is rotated or south-up): load the "
                   "map whole, or make it north-up first (gdalwarp)", "area");
  n.metres = cellMetres(n.srs, n.gt, n.info.sourceRows);
  if (!(n.metres.dx > 0 && n.metres.dy > 0 && std::isfinite(n.metres.dx) && std::isfinite(n.metres.dy)))
    failFile(path, "the georeferencing gives cells of " + exactNumber(n.metres.dx) + " x " +
                       exactNumber(n.metres.dy) + " m, not a positive size",
             "geotransform.pixel_width");
  return n;
}

GeoReference geoOf(const std::array<double, 6>& gt, OGRSpatialReferenceH srs, bool valid) {
  GeoReference g;
  g.valid = valid;
  g.geotransform = gt;
  if (srs) {
    char* wkt = nullptr;
    if (OSRExportToWkt(srs, &wkt) == OGRERR_NONE && wkt) g.crsWkt = wkt;
    CPLFree(wkt);
  }
  return g;
}

}  // namespace

DemHeader readDemHeader(const std::string& path) {
  ensureGdal();
  GdalErrorLog errors;
  NativeGrid n = openNative(path);
  DemHeader h;
  h.geometry = GridGeometry{n.info.sourceRows, n.info.sourceCols, n.metres.dx, n.metres.dy};
  h.rowCellWidth = n.metres.rowCellWidth;
  h.geo = geoOf(n.gt, n.srs, n.info.georeferenced);
  h.info = n.info;
  return h;
}

LoadedDem loadDemWindow(const std::string& path, int row0, int col0, int rows, int cols, double verticalScale) {
  ensureGdal();
  GdalErrorLog errors;
  NativeGrid n = openNative(path);
  if (row0 < 0 || col0 < 0 || rows < 2 || cols < 2 || row0 + rows > n.info.sourceRows ||
      col0 + cols > n.info.sourceCols)
    failFile(path, "the window of " + std::to_string(cols) + " x " + std::to_string(rows) + " cells at column " +
                       std::to_string(col0) + ", row " + std::to_string(row0) + " does not lie on the raster's " +
                       std::to_string(n.info.sourceCols) + " x " + std::to_string(n.info.sourceRows) + " cells",
             "area");
  LoadedDem out;
  out.info = n.info;
  terrain::Dem& dem = out.dem;
  // The whole raster's cell sizes, so a window position plus the window's origin is the map's
  // position (the local frame's x is col × cellWidth whatever the row); the window's own rows'
  // widths for a geographic map.
  dem.z = Raster<float>(GridGeometry{rows, cols, n.metres.dx, n.metres.dy}, 0.0f);
  if (!n.metres.rowCellWidth.empty())
    dem.rowCellWidth.assign(n.metres.rowCellWidth.begin() + row0, n.metres.rowCellWidth.begin() + row0 + rows);
  LoadOptions opt;
  opt.verticalScale = verticalScale;
  // Only the blocks the window touches are read (a tiled or striped GeoTIFF: its tiles or strips
  // over those rows), so the cost follows the window, not the raster.
  readHeights(n.src.get(), n.info.nodata.has_value(), opt, dem.z, out.info, path, col0, row0);
  std::array<double, 6> gt = n.gt;
  gt[0] += col0 * gt[1];
  gt[3] += row0 * gt[5];
  dem.z.geo = geoOf(gt, n.srs, n.info.georeferenced);
  return out;
}

LoadedDem loadDem(const std::string& path, const LoadOptions& opt) {
  ensureGdal();
  const UploadSandbox* sandbox = opt.upload;
  if (sandbox && !sandbox->live()) throw std::logic_error("loadDem: the upload sandbox is not live on this thread");
  // A user's file is named as uploaded, never by the server's path.
  const std::string shown = sandbox ? sandbox->uploadName(path) : path;
  checkOptions(opt, shown);
  GdalErrorLog errors;  // GDAL's own words stay here; users get ours
  Dataset src = openSource(path, sandbox, shown);

  LoadedDem out;
  DemInfo& info = out.info;
  info.path = shown;
  describeSource(src.get(), info);
  SourceGrid source;
  source.cols = info.sourceCols;
  source.rows = info.sourceRows;
  source.geographic = info.geographic;
  source.nodata = info.nodata;
  source.srs = GDALGetSpatialRef(src.get());
  source.georeferenced = info.georeferenced = GDALGetGeoTransform(src.get(), source.gt.data()) == CE_None;
  if (info.georeferenced)
    checkGeotransform(source.gt, info.sourceRows, info.sourceCols, source.srs, shown);
  else  // No georeferencing: pixels taken as 1 m, north-up, origin at the lower-left corner.
    source.gt = {0, 1, 0, static_cast<double>(info.sourceRows), 0, -1};

  // The grid it is planned on: band 1 as it is, or the warper's (crop, cell size, north-up).
  const GridPlan plan = planGrid(source, opt, shown);
  std::array<double, 6> gt = source.gt;
  OGRSpatialReferenceH srs = source.srs;
  Dataset warped;
  GDALDatasetH grid = src.get();
  if (plan.warped()) {
    info.resampling = plan.resampling;
    warped = warpToVrt(src.get(), plan.warpArgs, shown, !sandbox);
    grid = warped.get();
    GDALGetGeoTransform(grid, gt.data());
    srs = GDALGetSpatialRef(grid);
    checkGeotransform(gt, GDALGetRasterYSize(grid), GDALGetRasterXSize(grid), srs, shown);
  }
  // A GeoTIFF read as it is: opened again with GDAL's multi-threaded decoding (GDAL_NUM_THREADS,
  // read by the GTiff driver), which decodes the tiles or strips a read spans on all cores straight
  // into the grid, past the block cache. On a 7000² DEFLATE upload the read's peak fell from 426 to
  // 228 MiB (the block cache had filled to its 256 MiB cap with blocks read once) for 8 % less CPU.
  // The threads only decode bytes read through the handle already open (no file is opened off
  // this thread, where the upload sandbox does not reach); a warped read keeps the block cache
  // (the warper reads overlapping windows). At most 4 threads: each reserves a stack and decode
  // buffers inside the worker's address-space limit (server/jail), which a many-core host must not
  // spend before the grid.
  std::optional<ThreadConfig> decodeThreads;
  Dataset threaded;
  if (!warped && info.driver == "GTiff") {
    const std::string threads = std::to_string(std::clamp(std::thread::hardware_concurrency(), 1u, 4u));
    decodeThreads.emplace("GDAL_NUM_THREADS", threads.c_str());
    threaded = openSource(path, sandbox, shown);
    if (GDALGetRasterXSize(threaded.get()) != info.sourceCols || GDALGetRasterYSize(threaded.get()) != info.sourceRows)
      failFile(shown, "the file reads differently when opened twice");
    grid = threaded.get();
    srs = GDALGetSpatialRef(grid);
  }
  const int cols = GDALGetRasterXSize(grid), rows = GDALGetRasterYSize(grid);
  if (static_cast<std::int64_t>(cols) * rows > opt.maxCells)
    failFile(shown, "raster of " + std::to_string(rows) + " x " + std::to_string(cols) +
                        " cells exceeds the cell budget of " + std::to_string(opt.maxCells),
             "max_cells");
  if (rows < 2 || cols < 2) failFile(shown, "raster is smaller than 2 x 2 cells");

  terrain::Dem& dem = out.dem;
  CellMetres metres = cellMetres(srs, gt, rows);
  dem.rowCellWidth = std::move(metres.rowCellWidth);
  // Whatever the CRS, the grid's cells must be a real size in metres (no planner can use a map
  // whose cell is NaN, zero or infinite: core refuses it too, checkGridGeometry).
  if (!(metres.dx > 0 && metres.dy > 0 && std::isfinite(metres.dx) && std::isfinite(metres.dy)))
    failFile(shown, "the georeferencing gives cells of " + exactNumber(metres.dx) + " x " + exactNumber(metres.dy) +
                        " m, not a positive size",
             "geotransform.pixel_width");
  dem.z = Raster<float>(GridGeometry{rows, cols, metres.dx, metres.dy}, 0.0f);
  readHeights(grid, info.nodata && !warped, opt, dem.z, info, shown);

  dem.z.geo.valid = info.georeferenced;
  dem.z.geo.geotransform = gt;
  if (srs) {
    char* wkt = nullptr;
    if (OSRExportToWkt(srs, &wkt) == OGRERR_NONE && wkt) dem.z.geo.crsWkt = wkt;
    CPLFree(wkt);
  }
  return out;
}

namespace {

// Creates PATH.tmp, hands it to `fill`, then renames it over PATH.
template <class Fill>
void writeAtomically(const std::string& path, GDALDataType type, const GridGeometry& g,
                     const GeoReference& geo, Fill&& fill) {
  ensureGdal();
  const std::string tmp = path + ".tmp";
  // Floats with the floating-point predictor (byte planes of differences compress far better:
  // issue 22, a smooth PDM raster); the class bytes without.
  const char* options[] = {"COMPRESS=DEFLATE", "ZLEVEL=1", "TILED=YES", "BIGTIFF=IF_SAFER",
                           type == GDT_Float32 ? "PREDICTOR=3" : nullptr, nullptr};
  GDALDriverH drv = GDALGetDriverByName("GTiff");
  CPLErrorReset();
  errno = 0;
  Dataset ds(GDALCreate(drv, tmp.c_str(), g.cols, g.rows, 1, type, const_cast<char**>(options)));
  if (!ds) {
    if (lacksSpace(path, errno, 0))
      throw DiskFull(std::filesystem::path(path).filename().string());
    failFile(path, "cannot create the GeoTIFF" + gdalMessage(), "out");
  }
  double gt[6] = {0, g.cellWidth, 0, g.rows * g.cellHeight, 0, -g.cellHeight};
  if (geo.valid) std::copy(geo.geotransform.begin(), geo.geotransform.end(), gt);
  GDALSetGeoTransform(ds.get(), gt);
  if (!geo.crsWkt.empty()) GDALSetProjection(ds.get(), geo.crsWkt.c_str());
  errno = 0;
  std::error_code ec;
  bool ok = false;
  try {
    ok = fill(GDALGetRasterBand(ds.get(), 1));
  } catch (...) {
    // What fill reads failed (a band's source): no half-written file stays behind.
    ds.reset();
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    throw;
  }
  ds.reset();  // flushes and closes
  const int writeErrno = errno;
  if (!ok || CPLGetLastErrorType() >= CE_Failure) {
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    if (lacksSpace(path, writeErrno, static_cast<double>(g.rows) * g.cols * GDALGetDataTypeSizeBytes(type)))
      throw DiskFull(std::filesystem::path(path).filename().string());
    failFile(path, "cannot write the GeoTIFF" + gdalMessage(), "out");
  }
  // GDAL keeps what TIFF tags cannot hold (category names) in a .aux.xml sidecar: move it along,
  // sidecar first, so the GeoTIFF never appears without it.
  if (std::filesystem::exists(tmp + ".aux.xml", ec)) std::filesystem::rename(tmp + ".aux.xml", path + ".aux.xml", ec);
  std::filesystem::rename(tmp, path, ec);
  if (ec) failFile(path, "cannot move the GeoTIFF into place: " + ec.message(), "out");
}

}  // namespace

void writeGeoTiffInBands(const std::string& path, const GridGeometry& g, const GeoReference& geo, int bandRows,
                         const std::function<int(float* out)>& next) {
  constexpr float kNoData = -9999.0f;
  bandRows = std::max(1, bandRows);
  writeAtomically(path, GDT_Float32, g, geo, [&](GDALRasterBandH band) {
    GDALSetRasterNoDataValue(band, kNoData);
    int blockCols = 0, blockRows = 0;
    GDALGetBlockSize(band, &blockCols, &blockRows);
    std::vector<float> values(static_cast<std::size_t>(bandRows) * g.cols);
    for (int r = 0; r < g.rows;) {
      const int n = next(values.data());
      if (n < 1 || n > bandRows || n > g.rows - r)
        throw std::logic_error("writeGeoTiffInBands: a band of " + std::to_string(n) + " rows");
      float* v = values.data();
      for (std::size_t i = 0, m = static_cast<std::size_t>(n) * g.cols; i < m; ++i)
        if (std::isnan(v[i])) v[i] = kNoData;
      if (GDALRasterIO(band, GF_Write, 0, r, g.cols, n, v, g.cols, n, GDT_Float32, 0, 0) != CE_None)
        return false;
      r += n;
      // A finished row of tiles is compressed and written now, not held in GDAL's block cache
      // (up to GDAL_CACHEMAX of dirty blocks) until the file closes; a tile written before its
      // last row would be written again, its first copy left in the file as dead bytes.
      if (blockRows > 0 && (r % blockRows == 0 || r == g.rows) && GDALFlushRasterCache(band) != CE_None)
        return false;
    }
    return true;
  });
}

void writeGeoTiff(const std::string& path, const Raster<float>& layer) {
  const GridGeometry& g = layer.geometry;
  constexpr int kBandRows = 256;
  int row = 0;
  writeGeoTiffInBands(path, g, layer.geo, kBandRows, [&](float* out) {
    const int n = std::min(kBandRows, g.rows - row);
    std::copy_n(&layer(row, 0), static_cast<std::size_t>(n) * g.cols, out);
    row += n;
    return n;
  });
}

void writeClassesGeoTiff(const std::string& path, const Raster<std::uint8_t>& classes) {
  writeAtomically(path, GDT_Byte, classes.geometry, classes.geo, [&](GDALRasterBandH band) {
    GDALSetRasterNoDataValue(band, static_cast<double>(terrain::TerrainClass::NoData));
    GDALColorTableH ct = GDALCreateColorTable(GPI_RGB);
    const GDALColorEntry colours[4] = {
        {46, 160, 67, 255}, {245, 166, 35, 255}, {208, 2, 27, 255}, {0, 0, 0, 0}};
    for (int i = 0; i < 4; ++i) GDALSetColorEntry(ct, i, &colours[i]);
    GDALSetRasterColorTable(band, ct);
    GDALDestroyColorTable(ct);
    const char* names[] = {"traversable", "high_risk", "impassable", "nodata", nullptr};
    GDALSetRasterCategoryNames(band, const_cast<char**>(names));
    const GridGeometry& g = classes.geometry;
    return GDALRasterIO(band, GF_Write, 0, 0, g.cols, g.rows,
                        const_cast<std::uint8_t*>(classes.values.data()), g.cols, g.rows, GDT_Byte,
                        0, 0) == CE_None;
  });
}

}  // namespace rover::maps
