#include "maps/dem_grid_plan.hpp"

#include <cpl_conv.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <sstream>

#include "maps/dem_error.hpp"

namespace rover::maps {

std::string exactNumber(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

namespace {

const char* resamplingFor(const std::string& requested, double from, double to) {
  if (requested != "auto") return requested.c_str();
  // Shrinking averages the cells that fall together; enlarging interpolates (issue: terrain).
  if (to > from * 1.0001) return "average";
  if (to < from * 0.9999) return "bilinear";
  return "near";
}

// A pixel window is the CRS window of those pixels' outer edges.
std::optional<std::array<double, 4>> cropWindow(const SourceGrid& src, const LoadOptions& opt, bool rotated,
                                                const std::string& shown) {
  if (!opt.cropPixels) return opt.crop;
  const auto& w = *opt.cropPixels;
  const auto& gt = src.gt;
  if (opt.crop) failFile(shown, "give a crop window in CRS units or in pixels, not both", "crop_px");
  if (!(w[0] >= 0 && w[1] >= 0 && w[2] > 0 && w[3] > 0) || w[0] + w[2] > src.cols || w[1] + w[3] > src.rows)
    failFile(shown, "the pixel window lies outside the raster's " + std::to_string(src.cols) + " x " +
                        std::to_string(src.rows) + " pixels (columns x rows)",
             "crop_px");
  if (rotated) failFile(shown, "a pixel window needs a north-up (unrotated) raster", "crop_px");
  const double ya = gt[3] + w[1] * gt[5], yb = gt[3] + (w[1] + w[3]) * gt[5];
  return std::array<double, 4>{gt[0] + w[0] * gt[1], std::min(ya, yb), w[2] * std::fabs(gt[1]),
                               w[3] * std::fabs(gt[5])};
}

}  // namespace

GridPlan planGrid(const SourceGrid& src, const LoadOptions& opt, const std::string& shown) {
  const auto& gt = src.gt;
  const auto num = exactNumber;
  const bool rotated = gt[2] != 0 || gt[4] != 0;
  const bool southUp = gt[5] > 0;
  // An upload's own grid is bounded too, before the warper reads it (a tiny file may declare a
  // huge sparse raster).
  if (opt.upload && static_cast<std::int64_t>(src.cols) * src.rows > 4 * opt.maxCells)
    failFile(shown, "the file's raster of " + std::to_string(src.rows) + " x " + std::to_string(src.cols) +
                        " cells exceeds the source budget of " + std::to_string(4 * opt.maxCells) + " cells",
             "max_cells");
  const std::optional<std::array<double, 4>> crop = cropWindow(src, opt, rotated, shown);
  GridPlan plan;
  if (!(opt.cellSize > 0 || crop || rotated || southUp)) return plan;
  if (!src.georeferenced)
    failFile(shown, "cropping or resampling needs a georeferenced file", opt.cropPixels ? "crop_px" : "crop");
  std::vector<std::string>& args = plan.warpArgs;
  args = {"-of", "VRT", "-ot", "Float32", "-dstnodata", "nan", "-wo", "NUM_THREADS=ALL_CPUS"};
  if (src.nodata) args.insert(args.end(), {"-srcnodata", num(*src.nodata)});
  const double nativeRes = std::fabs(gt[1]);
  if (crop) {
    const auto& c = *crop;
    if (!(c[2] > 0 && c[3] > 0) || !std::isfinite(c[0] + c[1] + c[2] + c[3]))
      failFile(shown, "crop width and height must be positive", "crop");
    if (!rotated) {
      double x0 = gt[0], x1 = gt[0] + src.cols * gt[1];
      double y0 = gt[3] + src.rows * gt[5], y1 = gt[3];
      if (southUp) std::swap(y0, y1);
      if (c[0] >= x1 || c[0] + c[2] <= x0 || c[1] >= y1 || c[1] + c[3] <= y0)
        failFile(shown, "the crop window lies outside the raster", "crop");
    }
    args.insert(args.end(), {"-te", num(c[0]), num(c[1]), num(c[0] + c[2]), num(c[1] + c[3])});
  }
  if (opt.cellSize > 0) {
    double nativeMetres = nativeRes, metresPerUnitY = 1.0;
    OGRSpatialReferenceH srs = src.srs;
    if (src.geographic) {
      // Resample in metres: an equidistant cylindrical projection centred on the raster, on the
      // file's own ellipsoid or sphere.
      OGRErr e1 = OGRERR_NONE, e2 = OGRERR_NONE;
      double a = OSRGetSemiMajor(srs, &e1), b = OSRGetSemiMinor(srs, &e2);
      double unit = OSRGetAngularUnits(srs, nullptr);
      double lon = gt[0] + gt[1] * src.cols / 2.0, lat = gt[3] + gt[5] * src.rows / 2.0;
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
    const double widthM = (crop ? (*crop)[2] : src.cols * std::fabs(gt[1])) * metresPerUnitX;
    const double heightM = (crop ? (*crop)[3] : src.rows * std::fabs(gt[5])) * metresPerUnitY;
    if (!rotated && opt.cellSize * 2 > std::min(widthM, heightM))
      failFile(shown, "a cell size of " + num(opt.cellSize) + " m is larger than the map allows: the map is " +
                          num(std::round(widthM * 10) / 10) + " x " + num(std::round(heightM * 10) / 10) +
                          " m, so a cell can be at most " + num(std::floor(std::min(widthM, heightM) / 2 * 100) / 100) +
                          " m (2 x 2 cells)",
               "cell");
    plan.resampling = resamplingFor(opt.resampling, nativeMetres, opt.cellSize);
    args.insert(args.end(), {"-tr", num(opt.cellSize), num(opt.cellSize), "-r", plan.resampling});
  } else if (!rotated) {
    plan.resampling = opt.resampling == "auto" ? "near" : opt.resampling;
    args.insert(args.end(), {"-tr", num(std::fabs(gt[1])), num(std::fabs(gt[5])), "-r", plan.resampling});
  } else {
    plan.resampling = opt.resampling == "auto" ? "bilinear" : opt.resampling;
    args.insert(args.end(), {"-r", plan.resampling});
  }
  return plan;
}

}  // namespace rover::maps
