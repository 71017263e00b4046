#pragma once
// Options shared by every command that reads a DEM: cell size, crop window, vertical scale,
// resampling and the cell budget.
#include "maps/dem_io.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

// `cellOption` is the name of the resampling option ("cell", or "coverage-cell" for coverage).
void addDemOptions(ArgParser& args, const std::string& cellOption = "cell",
                   const std::string& cellDefault = "native");
maps::LoadOptions readDemOptions(const ArgParser& args, const std::string& cellOption = "cell",
                                 double cellDefault = 0);
// Loads a DEM, turning loader errors into one-line usage errors ("FILE: reason").
maps::LoadedDem loadDemOrFail(const std::string& path, const maps::LoadOptions& options);

}  // namespace rover::cli
