#pragma once
// GET /api/missions/{id}/map.png | map.tif (issue 13): the finished mission's map rendered on the
// server from its stored result (result.json, grid.bin, the request's keep_out) over its map's
// DEM, made on first request and kept in the mission's folder (deleted with it).
#include <string>

#include "server/api/routes.hpp"

namespace rover::api {

// The file's path; `format` is "png" (map + legends) or "tif" (the map part as an RGBA GeoTIFF
// in the map's CRS). Throws ApiError 409 when the mission has no result yet or its map was
// deleted.
std::string missionMapFile(ApiContext& ctx, const store::MissionRecord& m, const std::string& format);

}  // namespace rover::api
