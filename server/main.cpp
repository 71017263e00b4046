// roverplan: the one program (DESIGN.md) — subcommands for planning, experiments and benchmarks.
#include <iostream>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/jail/import_worker.hpp"

namespace {

const char* kUsage =
    "usage: roverplan <command> [options]\n"
    "\n"
    "commands:\n"
    "  serve      the planning server: REST API, live WebSocket streams, the web page\n"
    "  coverage   myopic coverage path planning on a random grid world (papers 002/000)\n"
    "  mission    a team mission on a DEM: LHC_GW_CONV route, RRT*, simulation, coordination "
    "(paper 001)\n"
    "  sweep      many seeded runs on all cores, summarised (--preset "
    "laine-fig6|laine-fig8|frontier|swinton)\n"
    "  study      studies into one SQLite database: run (threads, --shard K/N, mpirun), merge, "
    "summary, dump,\n"
    "             export --ompl (an OMPL benchmark database for Planner Arena)\n"
    "  bench      benchmarks that print their figures (bench coverage|mission|localisation)\n"
    "  terrain    synthetic moon/mars terrain as a GeoTIFF (the default map)\n"
    "  traversability  traversability classes and their shares from any DEM GDAL reads\n"
    "  slope      Horn slope (degrees) as a GeoTIFF, as gdaldem slope\n"
    "  layer      one terrain layer as a GeoTIFF (elevation, slope, aspect, hillshade, worst-slope)\n"
    "  pdm        a probability distribution map on a DEM's grid (Gaussians, random, raster)\n"
    "  render     a colourised PNG of a layer with a legend\n"
    "  version    print versions\n"
    "\n"
    "Run 'roverplan <command> --help' for the options of a command.\n";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  try {
    // Not in the usage: the process the server parses a client's file in (server/jail/).
    if (command == "import-worker") return rover::jail::importWorkerMain(args);
    if (command == "serve") return rover::cli::serveCommand(args, std::cout);
    if (command == "coverage") return rover::cli::coverageCommand(args, std::cout);
    if (command == "mission") return rover::cli::missionCommand(args, std::cout);
    if (command == "sweep") return rover::cli::sweepCommand(args, std::cout);
    if (command == "study") return rover::cli::studyCommand(args, std::cout);
    if (command == "bench") return rover::cli::benchCommand(args, std::cout);
    if (command == "terrain") return rover::cli::terrainCommand(args, std::cout);
    if (command == "traversability") return rover::cli::traversabilityCommand(args, std::cout);
    if (command == "slope") return rover::cli::layerCommand(args, std::cout, "slope");
    if (command == "layer") return rover::cli::layerCommand(args, std::cout, "");
    if (command == "pdm") return rover::cli::pdmCommand(args, std::cout);
    if (command == "render") return rover::cli::renderCommand(args, std::cout);
    if (command == "version" || command == "--version") {
      std::cout << "roverplan 0.1.0 (" << rover::maps::gdalVersion() << ")\n";
      return 0;
    }
    std::cerr << "roverplan: unknown command '" << command << "' (see roverplan --help)\n";
    return 2;
  } catch (const rover::cli::UsageError& e) {
    std::cerr << "roverplan " << command << ": " << e.what() << "\n";
    return 2;
  } catch (const rover::Error& e) {
    std::cerr << "roverplan " << command << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "roverplan " << command << ": internal error: " << e.what() << "\n";
    return 1;
  }
}
