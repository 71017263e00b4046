#pragma once
// Honest scale (issue 27): what the operator states one rover can do in a mission, checked against
// what each rover of the run did. Coverage for two micro-rovers on a map of 138 × 465 m pixels
// planned 24 647 km and 137 MJ without a word; with the rover's range stated, such a run ends
// "completed with warnings" saying which rover went how far past it. Never a refusal: the plan is
// still the answer to what was asked.
#include <span>
#include <string>
#include <vector>

namespace rover::planning {

struct RoverRange {
  double rangeM = 0;   // farthest one rover may drive in a mission; 0 = not stated   [rover_range_m]
  double energyJ = 0;  // energy one rover's battery holds for a mission; 0 = not stated [rover_energy_j]
};

// One line per stated limit that some rover went past, naming the parameter, its value, the
// rovers past it (numbered from 1, as people count) and the worst value reached. Rovers are
// indexed alike in both spans (either may be empty: not known).
std::vector<std::string> rangeWarnings(const RoverRange& range, std::span<const double> distanceM,
                                       std::span<const double> energyJ);

}  // namespace rover::planning
