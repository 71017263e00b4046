#pragma once
// A finished mission's map as one picture (issue 13: exports a GIS user can use): the hillshaded
// elevation at the DEM's own pixels (at most kMissionMapMaxSide a side: a bigger DEM is given
// here already resampled, maps::MapCatalog::demAtCell), the coverage grid's visited cells, each
// rover's track, the team route and its targets coloured by status, keep-out zones, incidents,
// and a scale bar; below it the elevation legend and a legend of what is drawn.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/planning/plan_result.hpp"
#include "core/terrain/dem.hpp"
#include "maps/geojson.hpp"
#include "maps/render.hpp"

namespace rover::maps {

inline constexpr int kMissionMapMaxSide = 4096;

struct MissionMapInput {
  const terrain::Dem* dem = nullptr;  // required; its extent is the map's
  std::string title;                  // e.g. "mission m12 · team-search"
  std::vector<Track> tracks;          // points (and believed points) in the local frame
  std::vector<Eigen::Vector2d> route;
  std::vector<RouteTarget> targets;
  std::vector<Zone> zones;
  std::vector<Incident> incidents;
  // Coverage: the final grid (row 0 north, 3 = visited, 2 = obstacle); empty for none.
  GridGeometry coverageGrid;
  std::vector<std::uint8_t> coverageStates;
};

struct MissionMap {
  Image image;                // map at the top-left, legends below
  int mapWidth = 0, mapHeight = 0;  // the map part, in pixels
};

// Throws rover::Error (InvalidInput, "dem") without a DEM or for one bigger than the cap.
MissionMap renderMissionMap(const MissionMapInput& in);

// The map part alone as an RGBA GeoTIFF (DEFLATE) in the map's CRS: `geo` is the georeferencing
// of the map's own grid `mapGrid`; the picture's pixels are scaled to span the same extent.
std::vector<std::uint8_t> encodeMissionMapGeoTiff(const MissionMap& m, const GridGeometry& mapGrid,
                                                  const GeoReference& geo);

}  // namespace rover::maps
