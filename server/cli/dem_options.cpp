#include "server/cli/dem_options.hpp"

#include "core/common/error.hpp"

namespace rover::cli {

void addDemOptions(ArgParser& a, const std::string& cellOption, const std::string& cellDefault) {
  a.option(cellOption, "M", cellDefault, "Resample to cells of M metres (GDAL warper: average when "
                                         "shrinking, bilinear when enlarging).");
  a.option("crop", "X0,Y0,W,H", "", "Window in the file's CRS units: lower-left corner, width, height.");
  a.option("vertical-scale", "K", "1", "Multiply heights by K (for files whose values are not metres).");
  a.option("resampling", "ALG", "auto", "auto | near | average | bilinear | cubic.");
  a.option("max-cells", "N", "200000000", "Refuse rasters larger than N cells (checked before reading).");
}

maps::LoadOptions readDemOptions(const ArgParser& a, const std::string& cellOption,
                                 double cellDefault) {
  maps::LoadOptions o;
  o.cellSize = a.has(cellOption) ? a.real(cellOption, 0, 1e-6, 1e7) : cellDefault;
  if (a.has("crop")) {
    auto v = a.realList("crop");
    if (v.size() != 4) throw UsageError("invalid value for --crop: expected X0,Y0,W,H");
    o.crop = std::array<double, 4>{v[0], v[1], v[2], v[3]};
  }
  o.verticalScale = a.real("vertical-scale", 1.0, -1e9, 1e9);
  o.resampling = a.str("resampling", "auto");
  o.maxCells = a.integer("max-cells", o.maxCells, 4, INT64_MAX);
  return o;
}

maps::LoadedDem loadDemOrFail(const std::string& path, const maps::LoadOptions& options) {
  try {
    return maps::loadDem(path, options);
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
}

}  // namespace rover::cli
