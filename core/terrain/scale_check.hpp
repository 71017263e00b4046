#pragma once
// Honest scale (issue 27): what a map's cell size and heights say about whether it is usable by a
// micro-rover, told to the operator as warnings at upload, in the map's description and in the
// mission form. Never a refusal: a coarse map still plans (a study on MOLA is a valid study), but
// the operator is told what the numbers mean before a mission reports 24 647 km of driving.
#include <string>
#include <vector>

#include "core/terrain/body.hpp"

namespace rover::terrain {

struct ScaleWarning {
  std::string code;     // coarse_cell | heights_look_like_radii | heights_out_of_range
  std::string field;    // the import option that would fix it: cell | vertical_offset | vertical_scale
  std::string message;  // one line for the operator, with the values that raised it
};

// The coarsest cell a micro-rover plan is meaningful on (m): paper 001's rovers sense a 1 m disc
// and keep 1 m apart on 0.25–1 m DEMs; paper 000's grid cell is the rover's footprint. At 5 m a
// single cell already averages away every slope and rock a micro-rover must avoid.
inline constexpr double kCoarsestRoverCell = 5.0;

// The heights a body's surface takes, in metres from its reference (sphere or areoid), widened
// by 0.5 km: Earth −10.9 km (Challenger Deep) to +8.8 km (Everest); Moon −9.1 to +10.8 km (LOLA,
// Smith et al. 2010); Mars −8.2 km (Hellas) to +21.9 km (Olympus Mons, MOLA). Unknown: their union.
struct HeightRange {
  double low, high;
};
HeightRange plausibleHeights(Body b);

// The mean radius a file of planetary radii would hold (m): Moon 1 737 400, Mars 3 396 190,
// Earth 6 371 000; 0 for Unknown.
double referenceRadius(Body b);

// The warnings for a map of `cellWidth` × `cellHeight` metre cells whose finite heights span
// [minHeight, maxHeight] on `body`. Empty when nothing looks wrong; NaN heights (an all-nodata
// map) raise no height warning.
std::vector<ScaleWarning> scaleWarnings(double cellWidth, double cellHeight, double minHeight, double maxHeight,
                                        Body body);

}  // namespace rover::terrain
