#pragma once
// Keep-out zones at the JSON edge (issue 13): a GeoJSON FeatureCollection of Polygons, read into
// core's KeepOut and written back. Used by PUT /api/maps/{id}/zones, a mission request's
// `keep_out`, mission files and the CLI's --keep-out, so every door says the same thing.
//
// Limits (README, API): at most kMaxZones features and kMaxZoneVertices vertices in all (every
// ring, the closing position not counted), so the zones of a mission fit in its 64 KiB body; each
// ring closed (first position = last), at least 3 distinct points and a non-zero area; numbers
// finite with |v| <= 1e9 before any conversion; on a map, every vertex within the map grown by
// kZoneSlack of its larger side, and each zone overlapping the map. Errors are http::ApiError 400
// naming the field, e.g. "zones.features[2].geometry.coordinates".
#include <functional>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/grid/geometry.hpp"
#include "core/planning/keep_out.hpp"

namespace rover::json {

inline constexpr std::size_t kMaxZones = 64;
inline constexpr std::size_t kMaxZoneVertices = 1024;
inline constexpr double kZoneSlack = 0.1;
// A zones body or file (PUT /api/maps/{id}/zones, --keep-out) is at most 256 KiB.
inline constexpr std::size_t kMaxZonesFileBytes = std::size_t{256} << 10;

// `prefix` names the value's field ("zones", "keep_out"). `toLocal` (optional) converts each
// position first (a file in the map's CRS). `map` (optional) checks the zones against the map's
// extent in the local frame. Feature properties other than a "name" string are dropped.
KeepOut zonesFromJson(const nlohmann::json& value, const std::string& prefix,
                      const GridGeometry* map = nullptr,
                      const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& toLocal = {});

// The names of the features in `value` as accepted (index-aligned with the zones; "" when none).
std::vector<std::string> zoneNames(const nlohmann::json& value);

// Throws unless every zone of `zones` lies within/over the map (the extent check above).
void checkZonesOnMap(const KeepOut& zones, const GridGeometry& map, const std::string& prefix);

// A FeatureCollection of Polygons in the local frame; names as "name" properties when given.
nlohmann::json zonesToJson(const KeepOut& zones, const std::vector<std::string>& names = {});

}  // namespace rover::json
