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
#include <filesystem>
#include <functional>
#include <memory>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::maps {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason,
                       const std::string& field = "file") {
  throw Error(ErrorCode::InvalidInput, field, path + ": " + reason);
}

std::string gdalMessage() {
  std::string m = CPLGetLastErrorMsg();
  return m.empty() ? "" : " (" + m + ")";
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
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
  fail(shownPath, headerName + " describes " + std::to_string(rows) + " × " + std::to_string(cols) + " cells" +
                      (bands > 1 ? " in " + std::to_string(bands) + " bands" : "") +
                      (offset > 0 ? " after a header offset of " + num(offset) + " bytes" : "") + " but " + dataName +
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
    fail(shownPath, "its blocks of " + std::to_string(bx) + " × " + std::to_string(by) + " cells" +
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

// Runs GDAL's warper into a lazy in-memory VRT: nothing is read until RasterIO, so the size can be
// checked against the budget first.
// `detail` adds GDAL's own message (the command line's files are the user's own; an upload's
// messages never show GDAL internals).
Dataset warpToVrt(GDALDatasetH src, const std::vector<std::string>& args, const std::string& path, bool detail) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  GDALWarpAppOptions* opts = GDALWarpAppOptionsNew(argv.data(), nullptr);
  if (!opts) fail(path, "invalid warp options" + (detail ? gdalMessage() : ""));
  int usageError = 0;
  CPLErrorReset();
  GDALDatasetH out = GDALWarp("", nullptr, 1, &src, opts, &usageError);
  GDALWarpAppOptionsFree(opts);
  if (!out) fail(path, "cannot crop/resample" + (detail ? gdalMessage() : ""));
  return Dataset(out);
}

const char* resamplingFor(const std::string& requested, double from, double to) {
  if (requested != "auto") return requested.c_str();
  // Shrinking averages the cells that fall together; enlarging interpolates (issue: terrain).
  if (to > from * 1.0001) return "average";
  if (to < from * 0.9999) return "bilinear";
  return "near";
}

}  // namespace

LoadedDem loadDem(const std::string& path, const LoadOptions& opt) {
  ensureGdal();
  const UploadSandbox* sandbox = opt.upload;
  if (sandbox && !sandbox->live()) throw std::logic_error("loadDem: the upload sandbox is not live on this thread");
  // A user's file is named as uploaded, never by the server's path.
  const std::string shown = sandbox ? sandbox->uploadName(path) : path;
  VSIStatBufL st;
  if (VSIStatL(path.c_str(), &st) != 0) fail(shown, "no such file");
  if (!VSI_ISDIR(st.st_mode) && st.st_size == 0) fail(shown, "empty file");
  if (!(opt.verticalScale != 0) || !std::isfinite(opt.verticalScale))
    fail(shown, "vertical scale must be a finite non-zero number", "vertical_scale");
  if (opt.cellSize < 0 || !std::isfinite(opt.cellSize))
    fail(shown, "cell size must be a positive number of metres", "cell");
  const std::vector<std::string> algs{"auto", "near", "average", "bilinear", "cubic"};
  if (std::find(algs.begin(), algs.end(), opt.resampling) == algs.end())
    fail(shown, "resampling must be auto, near, average, bilinear or cubic", "resampling");

  GdalErrorLog errors;  // GDAL's own words stay here; users get ours
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
  if (!src) fail(shown, unreadableReason(path, sandbox != nullptr));
  if (GDALGetRasterCount(src.get()) < 1) fail(shown, "the file holds no raster band");
  checkRawDataSize(src.get(), GDALGetDriverShortName(GDALGetDatasetDriver(src.get())), shown,
                   [&](const std::string& f) { return sandbox ? sandbox->uploadName(f) : f; });
  checkBlockSize(src.get(), shown);

  LoadedDem out;
  DemInfo& info = out.info;
  info.path = shown;
  info.driver = GDALGetDriverShortName(GDALGetDatasetDriver(src.get()));
  info.sourceCols = GDALGetRasterXSize(src.get());
  info.sourceRows = GDALGetRasterYSize(src.get());
  GDALRasterBandH band = GDALGetRasterBand(src.get(), 1);
  int has = 0;
  double nodata = GDALGetRasterNoDataValue(band, &has);
  if (has) info.nodata = nodata;
  double scale = GDALGetRasterScale(band, &has);
  info.scale = has && scale != 0 ? scale : 1.0;
  double offset = GDALGetRasterOffset(band, &has);
  info.offset = has ? offset : 0.0;

  double gt[6];
  info.georeferenced = GDALGetGeoTransform(src.get(), gt) == CE_None;
  if (!info.georeferenced) {
    // No georeferencing: pixels taken as 1 m, north-up, origin at the lower-left corner.
    double fallback[6] = {0, 1, 0, static_cast<double>(info.sourceRows), 0, -1};
    std::copy(fallback, fallback + 6, gt);
  }
  OGRSpatialReferenceH srs = GDALGetSpatialRef(src.get());
  if (srs) {
    info.crsName = OSRGetName(srs) ? OSRGetName(srs) : "";
    info.geographic = OSRIsGeographic(srs);
  }
  // The file's georeferencing is the client's word: checked before any of it is used (issue 22).
  auto checkGeotransform = [&](const double* t, int r, int c, OGRSpatialReferenceH crs) {
    std::array<double, 6> a;
    std::copy(t, t + 6, a.begin());
    if (auto p = georefProblem(a, r, c, crsUnits(crs))) fail(shown, p->reason, p->field);
  };
  if (info.georeferenced) checkGeotransform(gt, info.sourceRows, info.sourceCols, srs);

  // Decide whether the warper has to build the grid: resampling, cropping, a rotated or south-up
  // geotransform. Otherwise band 1 is read as is.
  const bool rotated = gt[2] != 0 || gt[4] != 0;
  const bool southUp = gt[5] > 0;
  Dataset warped;
  GDALDatasetH grid = src.get();
  // An upload's own grid is bounded too, before the warper reads it (a tiny file may declare a
  // huge sparse raster).
  if (sandbox && static_cast<std::int64_t>(info.sourceCols) * info.sourceRows > 4 * opt.maxCells)
    fail(shown, "the file's raster of " + std::to_string(info.sourceRows) + " x " + std::to_string(info.sourceCols) +
                    " cells exceeds the source budget of " + std::to_string(4 * opt.maxCells) + " cells",
         "max_cells");
  // A pixel window is the CRS window of those pixels' outer edges.
  std::optional<std::array<double, 4>> crop = opt.crop;
  if (opt.cropPixels) {
    const auto& w = *opt.cropPixels;
    if (crop) fail(shown, "give a crop window in CRS units or in pixels, not both", "crop_px");
    if (!(w[0] >= 0 && w[1] >= 0 && w[2] > 0 && w[3] > 0) || w[0] + w[2] > info.sourceCols ||
        w[1] + w[3] > info.sourceRows)
      fail(shown, "the pixel window lies outside the raster's " + std::to_string(info.sourceCols) + " x " +
                      std::to_string(info.sourceRows) + " pixels (columns x rows)",
           "crop_px");
    if (rotated) fail(shown, "a pixel window needs a north-up (unrotated) raster", "crop_px");
    const double ya = gt[3] + w[1] * gt[5], yb = gt[3] + (w[1] + w[3]) * gt[5];
    crop = std::array<double, 4>{gt[0] + w[0] * gt[1], std::min(ya, yb), w[2] * std::fabs(gt[1]),
                                 w[3] * std::fabs(gt[5])};
  }
  if (opt.cellSize > 0 || crop || rotated || southUp) {
    if (!info.georeferenced)
      fail(shown, "cropping or resampling needs a georeferenced file", opt.cropPixels ? "crop_px" : "crop");
    std::vector<std::string> args{"-of", "VRT", "-ot", "Float32", "-dstnodata", "nan",
                                  "-wo", "NUM_THREADS=ALL_CPUS"};
    if (info.nodata) args.insert(args.end(), {"-srcnodata", num(*info.nodata)});
    double nativeRes = std::fabs(gt[1]);
    if (crop) {
      const auto& c = *crop;
      if (!(c[2] > 0 && c[3] > 0) || !std::isfinite(c[0] + c[1] + c[2] + c[3]))
        fail(shown, "crop width and height must be positive", "crop");
      if (!rotated) {
        double x0 = gt[0], x1 = gt[0] + info.sourceCols * gt[1];
        double y0 = gt[3] + info.sourceRows * gt[5], y1 = gt[3];
        if (southUp) std::swap(y0, y1);
        if (c[0] >= x1 || c[0] + c[2] <= x0 || c[1] >= y1 || c[1] + c[3] <= y0)
          fail(shown, "the crop window lies outside the raster", "crop");
      }
      args.insert(args.end(), {"-te", num(c[0]), num(c[1]), num(c[0] + c[2]), num(c[1] + c[3])});
    }
    if (opt.cellSize > 0) {
      double nativeMetres = nativeRes, metresPerUnitY = 1.0;
      if (info.geographic) {
        // Resample in metres: an equidistant cylindrical projection centred on the raster, on the
        // file's own ellipsoid or sphere.
        OGRErr e1 = OGRERR_NONE, e2 = OGRERR_NONE;
        double a = OSRGetSemiMajor(srs, &e1), b = OSRGetSemiMinor(srs, &e2);
        double unit = OSRGetAngularUnits(srs, nullptr);
        double lon = gt[0] + gt[1] * info.sourceCols / 2.0, lat = gt[3] + gt[5] * info.sourceRows / 2.0;
        if (crop) lon = (*crop)[0] + (*crop)[2] / 2, lat = (*crop)[1] + (*crop)[3] / 2;
        std::string proj = "+proj=eqc +lat_ts=" + num(lat * unit * 180 / std::numbers::pi) +
                           " +lon_0=" + num(lon * unit * 180 / std::numbers::pi) + " +a=" + num(a) +
                           " +b=" + num(b) + " +units=m +no_defs";
        args.insert(args.end(), {"-t_srs", proj});
        if (crop) {
          // The crop window stays in the file's own (geographic) units.
          char* wkt = nullptr;
          OSRExportToWkt(srs, &wkt);
          args.insert(args.end(), {"-te_srs", wkt ? wkt : ""});
          CPLFree(wkt);
        }
        nativeMetres = nativeRes * unit * a * std::cos(lat * unit);
        metresPerUnitY = unit * a;
      } else if (srs) {
        nativeMetres = nativeRes * OSRGetLinearUnits(srs, nullptr);
        metresPerUnitY = OSRGetLinearUnits(srs, nullptr);
      }
      // A cell that does not fit twice across the map leaves no grid: say so in metres.
      const double metresPerUnitX = nativeRes > 0 ? nativeMetres / nativeRes : 1.0;
      const double widthM = (crop ? (*crop)[2] : info.sourceCols * std::fabs(gt[1])) * metresPerUnitX;
      const double heightM = (crop ? (*crop)[3] : info.sourceRows * std::fabs(gt[5])) * metresPerUnitY;
      if (!rotated && opt.cellSize * 2 > std::min(widthM, heightM))
        fail(shown, "a cell size of " + num(opt.cellSize) + " m is larger than the map allows: the map is " +
                        num(std::round(widthM * 10) / 10) + " x " + num(std::round(heightM * 10) / 10) +
                        " m, so a cell can be at most " + num(std::floor(std::min(widthM, heightM) / 2 * 100) / 100) +
                        " m (2 x 2 cells)",
             "cell");
      info.resampling = resamplingFor(opt.resampling, nativeMetres, opt.cellSize);
      args.insert(args.end(), {"-tr", num(opt.cellSize), num(opt.cellSize), "-r", info.resampling});
    } else if (!rotated) {
      info.resampling = opt.resampling == "auto" ? "near" : opt.resampling;
      args.insert(args.end(), {"-tr", num(std::fabs(gt[1])), num(std::fabs(gt[5])), "-r", info.resampling});
    } else {
      info.resampling = opt.resampling == "auto" ? "bilinear" : opt.resampling;
      args.insert(args.end(), {"-r", info.resampling});
    }
    warped = warpToVrt(src.get(), args, shown, !sandbox);
    grid = warped.get();
    GDALGetGeoTransform(grid, gt);
    srs = GDALGetSpatialRef(grid);
    checkGeotransform(gt, GDALGetRasterYSize(grid), GDALGetRasterXSize(grid), srs);
  }

  const int cols = GDALGetRasterXSize(grid), rows = GDALGetRasterYSize(grid);
  if (static_cast<std::int64_t>(cols) * rows > opt.maxCells)
    fail(shown, "raster of " + std::to_string(rows) + " x " + std::to_string(cols) +
                   " cells exceeds the cell budget of " + std::to_string(opt.maxCells),
         "max_cells");
  if (rows < 2 || cols < 2) fail(shown, "raster is smaller than 2 x 2 cells");

  // Cell spacing in metres.
  terrain::Dem& dem = out.dem;
  double dx = std::fabs(gt[1]), dy = std::fabs(gt[5]);
  if (srs && OSRIsGeographic(srs)) {
    // Geographic CRS: metres from the CRS's own ellipsoid — the meridional radius of curvature
    // M(φ) north-south and N(φ)·cos φ east-west, per row.
    OGRErr e = OGRERR_NONE;
    double a = OSRGetSemiMajor(srs, &e), b = OSRGetSemiMinor(srs, &e);
    double e2 = 1.0 - (b * b) / (a * a), unit = OSRGetAngularUnits(srs, nullptr);
    auto latOf = [&](double row) { return (gt[3] + row * gt[5]) * unit; };
    auto M = [&](double phi) {
      double s = std::sin(phi);
      return a * (1 - e2) / std::pow(1 - e2 * s * s, 1.5);
    };
    auto N = [&](double phi) {
      double s = std::sin(phi);
      return a / std::sqrt(1 - e2 * s * s);
    };
    dem.rowCellWidth.resize(rows);
    for (int r = 0; r < rows; ++r) {
      double phi = latOf(r + 0.5);
      dem.rowCellWidth[r] = std::max(1e-6, N(phi) * std::cos(phi) * std::fabs(gt[1]) * unit);
    }
    double phiC = latOf(rows / 2.0);
    dy = M(phiC) * std::fabs(gt[5]) * unit;
    dx = std::max(1e-6, N(phiC) * std::cos(phiC) * std::fabs(gt[1]) * unit);
  } else if (srs) {
    double lu = OSRGetLinearUnits(srs, nullptr);
    dx *= lu;
    dy *= lu;
    const char* proj = OSRGetAttrValue(srs, "PROJECTION", 0);
    if (proj && std::string(proj) == SRS_PT_EQUIRECTANGULAR) {
      // Equidistant cylindrical (global PDS/ISIS products): x = R(λ−λ0)·cos φts, y = R(φ−φ0), so
      // one pixel spans dx·cos φ / cos φts on the ground. Without this, slopes towards the poles
      // of a global map come out far too gentle.
      OGRErr e = OGRERR_NONE;
      const double R = OSRGetSemiMajor(srs, &e);
      const double deg = std::numbers::pi / 180.0;
      const double phiTs = OSRGetProjParm(srs, SRS_PP_STANDARD_PARALLEL_1, 0.0, &e) * deg;
      const double phi0 = OSRGetProjParm(srs, SRS_PP_LATITUDE_OF_ORIGIN, 0.0, &e) * deg;
      const double fn = OSRGetProjParm(srs, SRS_PP_FALSE_NORTHING, 0.0, &e);
      dem.rowCellWidth.resize(rows);
      for (int r = 0; r < rows; ++r) {
        double phi = ((gt[3] + (r + 0.5) * gt[5]) * lu - fn) / R + phi0;
        dem.rowCellWidth[r] = std::max(1e-6, dx * std::cos(phi) / std::cos(phiTs));
      }
      double phiC = ((gt[3] + rows / 2.0 * gt[5]) * lu - fn) / R + phi0;
      dx = std::max(1e-6, dx * std::cos(phiC) / std::cos(phiTs));
    }
  }

  // Whatever the CRS, the grid's cells must be a real size in metres (no planner can use a map
  // whose cell is NaN, zero or infinite: core refuses it too, checkGridGeometry).
  if (!(dx > 0 && dy > 0 && std::isfinite(dx) && std::isfinite(dy)))
    fail(shown, "the georeferencing gives cells of " + num(dx) + " x " + num(dy) + " m, not a positive size",
         "geotransform.pixel_width");
  GridGeometry g{rows, cols, dx, dy};
  dem.z = Raster<float>(g, 0.0f);
  CPLErrorReset();
  if (GDALRasterIO(GDALGetRasterBand(grid, 1), GF_Read, 0, 0, cols, rows, dem.z.values.data(), cols,
                   rows, GDT_Float32, 0, 0) != CE_None)
    fail(shown, "truncated or corrupt " + formatInWords(info.driver) + " (its data does not read)" +
                    (sandbox ? "" : gdalMessage()));

  const bool compareNodata = info.nodata && !warped;
  const float nodataF = info.nodata ? static_cast<float>(*info.nodata) : 0.0f;
  const double k = info.scale * opt.verticalScale, o = info.offset * opt.verticalScale;
  float* z = dem.z.values.data();
  double lo = INFINITY, hi = -INFINITY;
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(rows) * cols; ++i) {
    float v = z[i];
    if (std::isnan(v) || (compareNodata && v == nodataF)) {
      z[i] = NAN;
      ++info.nodataCells;
      continue;
    }
    if (std::isinf(v)) fail(shown, "the raster holds infinite values");
    double h = v * k + o;
    z[i] = static_cast<float>(h);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  if (info.nodataCells == static_cast<std::int64_t>(rows) * cols) fail(shown, "every cell is nodata");
  info.minHeight = lo;
  info.maxHeight = hi;

  dem.z.geo.valid = info.georeferenced;
  std::copy(gt, gt + 6, dem.z.geo.geotransform.begin());
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
    fail(path, "cannot create the GeoTIFF" + gdalMessage(), "out");
  }
  double gt[6] = {0, g.cellWidth, 0, g.rows * g.cellHeight, 0, -g.cellHeight};
  if (geo.valid) std::copy(geo.geotransform.begin(), geo.geotransform.end(), gt);
  GDALSetGeoTransform(ds.get(), gt);
  if (!geo.crsWkt.empty()) GDALSetProjection(ds.get(), geo.crsWkt.c_str());
  errno = 0;
  bool ok = fill(GDALGetRasterBand(ds.get(), 1));
  ds.reset();  // flushes and closes
  const int writeErrno = errno;
  std::error_code ec;
  if (!ok || CPLGetLastErrorType() >= CE_Failure) {
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    if (lacksSpace(path, writeErrno, static_cast<double>(g.rows) * g.cols * GDALGetDataTypeSizeBytes(type)))
      throw DiskFull(std::filesystem::path(path).filename().string());
    fail(path, "cannot write the GeoTIFF" + gdalMessage(), "out");
  }
  // GDAL keeps what TIFF tags cannot hold (category names) in a .aux.xml sidecar: move it along,
  // sidecar first, so the GeoTIFF never appears without it.
  if (std::filesystem::exists(tmp + ".aux.xml", ec)) std::filesystem::rename(tmp + ".aux.xml", path + ".aux.xml", ec);
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(path, "cannot move the GeoTIFF into place: " + ec.message(), "out");
}

}  // namespace

void writeGeoTiff(const std::string& path, const Raster<float>& layer) {
  constexpr float kNoData = -9999.0f;
  writeAtomically(path, GDT_Float32, layer.geometry, layer.geo, [&](GDALRasterBandH band) {
    GDALSetRasterNoDataValue(band, kNoData);
    const GridGeometry& g = layer.geometry;
    std::vector<float> row(g.cols);
    for (int r = 0; r < g.rows; ++r) {
      for (int c = 0; c < g.cols; ++c) row[c] = std::isnan(layer(r, c)) ? kNoData : layer(r, c);
      if (GDALRasterIO(band, GF_Write, 0, r, g.cols, 1, row.data(), g.cols, 1, GDT_Float32, 0, 0) !=
          CE_None)
        return false;
    }
    return true;
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
