#pragma once
// GDAL process setup for the map data layer: drivers registered once, errors kept off stderr so
// they reach users as our own messages.
#include <string>

namespace rover::maps {

// Registers all GDAL drivers (thread-safe, idempotent).
void ensureGdal();
// "GDAL 3.6.2" — the runtime library's own release name.
std::string gdalVersion();

}  // namespace rover::maps
