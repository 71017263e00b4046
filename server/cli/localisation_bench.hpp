#pragma once
// `roverplan bench localisation` (issue 15): true coverage at the believed stop against the
// localisation error, seeded sweeps with and without loop closure (server/cli/localisation_bench.cpp).
#include <ostream>

#include "server/cli/arg_parser.hpp"

namespace rover::cli {

void addLocalisationBenchOptions(ArgParser& args);
int benchLocalisation(const ArgParser& args, int runs, std::ostream& out);

}  // namespace rover::cli
