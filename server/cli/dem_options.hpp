#pragma once
// Options shared by every command that reads a DEM: cell size, crop window, vertical scale,
// resampling and the cell budget.
#include "core/grid/raster.hpp"
#include "core/planning/mission_area.hpp"
#include "core/terrain/dem.hpp"
#include "maps/dem_import_options.hpp"
#include "maps/dem_io.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

// `cellOption` is the name of the resampling option ("cell", or "coverage-cell" for coverage).
void addDemOptions(ArgParser& args, const std::string& cellOption = "cell",
                   const std::string& cellDefault = "native");
// The options as read (the body too); a bad value is a one-line UsageError naming the option.
maps::DemImport readDemImport(const ArgParser& args, const std::string& cellOption = "cell");
maps::LoadOptions readDemOptions(const ArgParser& args, const std::string& cellOption = "cell",
                                 double cellDefault = 0);
// Loads a DEM, turning loader errors into one-line usage errors ("FILE: reason").
maps::LoadedDem loadDemOrFail(const std::string& path, const maps::LoadOptions& options);

// Where a PDM comes from: Gaussians JSON, G random Gaussians, or a raster of weights. The option
// names differ between `pdm` (--gaussians/--random/--raster) and `mission` (--pdm/--random-pdm/
// --pdm-raster); `seed` empty = the command's own --seed.
struct PdmOptionNames {
  std::string gaussians = "gaussians";
  std::string random = "random";
  std::string raster = "raster";
  std::string seed = "seed";
};
void addPdmOptions(ArgParser& args, const PdmOptionNames& names);
// A mission area's window (issue 24): `dem` is then the window of `map`, and the PDM's mass lies
// on the cells `inArea` marks, normalised there. Gaussians are in the map's frame; random ones
// are drawn over the window; a raster is read on the window's extent.
struct PdmArea {
  GridGeometry map;
  PlanningWindow window;
  std::vector<std::uint8_t> inArea;
};
// Exactly one source required unless `optional` (then an empty raster when none is given).
Raster<float> readPdmOptions(const ArgParser& args, const terrain::Dem& dem,
                             const PdmOptionNames& names, bool optional = false,
                             const PdmArea* area = nullptr);

}  // namespace rover::cli
