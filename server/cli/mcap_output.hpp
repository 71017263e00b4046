#pragma once
// `--mcap FILE` of `roverplan mission` and `roverplan coverage`: the replay written to FILE
// (server/exports/mission_mcap.hpp); a file that cannot be written is a UsageError naming it.
#include <string>

#include "server/exports/mission_mcap.hpp"

namespace rover::cli {

void writeMcapOrFail(const exports::ReplayInput& in, const std::string& path);

}  // namespace rover::cli
