#pragma once
// Options shared by `coverage`, `sweep` and `bench coverage`: the random world and every coverage
// planner parameter, generated from the planner's own parameter table so the CLI never drifts
// from the API.
#include "core/common/error.hpp"
#include "core/common/params.hpp"
#include "core/coverage/world.hpp"
#include "core/planning/planner.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

void addWorldOptions(ArgParser& args);
coverage::WorldParams readWorldOptions(const ArgParser& args);

void addCoverageParamOptions(ArgParser& args);
ParamSet readCoverageParamOptions(const ArgParser& args);

// One option per parameter of a planner's table (flags for booleans), `skip` keys left out.
void addParamOptions(ArgParser& args, const std::vector<ParamInfo>& infos,
                     const std::vector<std::string>& skip = {});
// The parameters given on the command line (defaults are left to the planner).
ParamSet readParamOptions(const ArgParser& args, const std::vector<ParamInfo>& infos,
                          const std::vector<std::string>& skip = {});

// --start "X,Y,DEG[;X,Y,DEG...]": rover starts in the local frame, headings in degrees (returned
// in radians); empty when the option is not given.
std::vector<RoverStart> readStartOption(const ArgParser& args);

// --keep-out FILE.geojson: keep-out zones, a FeatureCollection of Polygons in the local frame
// (server/json/zones_json.hpp), checked against `map` (the world or the DEM's grid). Empty
// when not given; a bad file is a UsageError naming the option and the field.
void addKeepOutOption(ArgParser& args);
KeepOut readKeepOutOption(const ArgParser& args, const GridGeometry& map);

// The option name of a planner parameter key (sense_radius -> sense, max_steps -> max-steps).
std::string optionForParam(const std::string& key);
// A core validation error, re-said in terms of the command's options.
[[noreturn]] void throwAsUsage(const Error& e);

}  // namespace rover::cli
