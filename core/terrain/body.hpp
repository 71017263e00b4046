#pragma once
// The planetary body a map lies on, and its constants (issue 11: body-aware defaults). Detected at
// the edge from the map's CRS (maps/georef.hpp); the core only reads names and numbers.
#include <string>

namespace rover::terrain {

enum class Body { Unknown, Earth, Moon, Mars };

// "earth", "moon", "mars", "unknown".
const char* bodyName(Body b);
// Mean surface gravity, m/s²: Earth 9.81, Moon 1.62, Mars 3.71; 0 for Unknown.
double bodyGravity(Body b);

// From a CRS's ellipsoid (or sphere) name, datum name and semi-major axis in metres. The axis
// decides when it matches a body (Mars 3 396 190 m IAU 2000, also the older 3 393.4 / 3 397 km
// spheres; Moon 1 737 400 m; Earth 6 378 137 m and the historical ellipsoids within 1 km); the
// names decide otherwise ("Mars_2000", "Moon_2000_IAU_IAG", "WGS 84", "GRS 1980", ...).
Body detectBody(const std::string& ellipsoidName, const std::string& datumName,
                double semiMajorAxis);

}  // namespace rover::terrain
