#pragma once
// How a DEM file becomes the grid it is planned on (DESIGN.md: maps/): band 1 read as it is, or
// GDAL's warper with a crop window (CRS units or pixels), a cell size in metres (geographic files
// resampled in an equidistant cylindrical projection centred on the window), and a rotated or
// south-up geotransform made north-up. Decided from the file's header before any cell is read, so
// every refusal (a window outside the raster, a cell the map cannot hold twice, an upload's source
// grid over its budget) comes before memory is spent.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <ogr_srs_api.h>

#include "maps/dem_io.hpp"

namespace rover::maps {

// What the file's header says of its grid.
struct SourceGrid {
  std::array<double, 6> gt{};  // the file's geotransform (checked), or the 1 m fallback
  int cols = 0, rows = 0;
  bool georeferenced = false;
  bool geographic = false;
  OGRSpatialReferenceH srs = nullptr;  // the file's CRS, or null
  std::optional<double> nodata;
};

struct GridPlan {
  std::vector<std::string> warpArgs;  // gdalwarp arguments (to a VRT); empty: band 1 read as is
  std::string resampling;             // the warper's algorithm, "" when read as is
  bool warped() const { return !warpArgs.empty(); }
};

// Throws rover::Error naming the option ("crop", "crop_px", "cell", "max_cells") for a request
// the file cannot meet. `shownPath` names the file in messages.
GridPlan planGrid(const SourceGrid& src, const LoadOptions& opt, const std::string& shownPath);

}  // namespace rover::maps
