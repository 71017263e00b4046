#include "server/cli/mcap_output.hpp"

#include <stdexcept>

#include "server/cli/arg_parser.hpp"

namespace rover::cli {

void writeMcapOrFail(const exports::ReplayInput& in, const std::string& path) {
  try {
    exports::writeReplayMcapFile(in, path);
  } catch (const std::runtime_error& e) {
    throw UsageError(path + ": " + e.what());
  }
}

}  // namespace rover::cli
