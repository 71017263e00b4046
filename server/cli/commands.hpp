#pragma once
// roverplan's subcommands. Each returns the process exit status; usage and input errors are thrown
// as UsageError / rover::Error and reported by main as one line with exit status 2.
#include <iosfwd>
#include <string>
#include <vector>

namespace rover::cli {

int coverageCommand(const std::vector<std::string>& args, std::ostream& out);
int missionCommand(const std::vector<std::string>& args, std::ostream& out);
int sweepCommand(const std::vector<std::string>& args, std::ostream& out);
// `study run | merge | summary | dump` (server/studies).
int studyCommand(const std::vector<std::string>& args, std::ostream& out);
int benchCommand(const std::vector<std::string>& args, std::ostream& out);
int terrainCommand(const std::vector<std::string>& args, std::ostream& out);
int traversabilityCommand(const std::vector<std::string>& args, std::ostream& out);
// `layer LAYER IN --out F.tif`; with `fixed` = "slope" it is the `slope IN --out F.tif` command.
int layerCommand(const std::vector<std::string>& args, std::ostream& out, const std::string& fixed);
int pdmCommand(const std::vector<std::string>& args, std::ostream& out);
int renderCommand(const std::vector<std::string>& args, std::ostream& out);
int serveCommand(const std::vector<std::string>& args, std::ostream& out);

}  // namespace rover::cli
