#pragma once
// roverplan's subcommands. Each returns the process exit status; usage and input errors are thrown
// as UsageError / rover::Error and reported by main as one line with exit status 2.
#include <iosfwd>
#include <string>
#include <vector>

namespace rover::cli {

int coverageCommand(const std::vector<std::string>& args, std::ostream& out);
int sweepCommand(const std::vector<std::string>& args, std::ostream& out);
int benchCommand(const std::vector<std::string>& args, std::ostream& out);

}  // namespace rover::cli
