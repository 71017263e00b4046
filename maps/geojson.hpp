#pragma once
// Rover paths as GeoJSON in the map's own CRS (issue: terrain layers, exports), written through
// OGR's GeoJSON driver so `ogrinfo` reads it back: one LineString feature per rover with its
// metrics as properties.
//
// Properties: "rover" (integer) and one real field per metric key (a metric named "rover" is
// stored as "rover_metric"; non-finite values are null). A one-point track is a Point feature,
// an empty one has a null geometry. A track with believed points (coverage under localisation
// error) is followed by a second feature, its believed track, with the same "rover"; both then
// carry "track": "true" or "believed" (the metrics on the true one). Coordinates go through localToCrs. The "crs" member names
// the map's CRS: "urn:ogc:def:crs:AUTH::CODE" when it has an authority code, else its WKT2 text
// (GDAL's reader takes both); none when geo.crsWkt is empty. Throws rover::Error
// (InvalidInput, "crs") for an unparsable CRS and (InvalidInput, "tracks") for non-finite points.
#include <string>
#include <vector>

#include "core/grid/raster.hpp"
#include "core/planning/plan_result.hpp"

namespace rover::maps {

// A keep-out polygon in the local frame: the outer ring, then holes (rings need not be closed).
struct Zone {
  std::vector<std::vector<Eigen::Vector2d>> rings;
  std::string name;
};

// Everything a mission's map shows (issue 13: exports a GIS user can use) from its result
// (tracks, the overlay keyed "route", targets, incidents) and its keep-out zones:
// one FeatureCollection (one OGR layer, "mission", mixed geometry) whose features carry a "layer"
// property saying what they are, in this order:
//   "track"    LineString per rover (and per believed track): rover, length_m, duration_s (team),
//              the track's metrics;
//   "route"    LineString: the team route from the start centre through the targets in order
//              (targets, length_m);
//   "target"   Point per route target: target (visiting order), status reached | short | skipped |
//              unreachable, legs_reached, legs_short, legs_skipped, legs_no_slot;
//   "zone"     Polygon per keep-out zone: zone (index), name;
//   "incident" Point: rover, kind, time_s (or step for a planner without a clock), other, note.
// CRS and errors as below.
std::string missionToGeoJson(const PlanResult& r, const std::vector<Zone>& zones, const GridGeometry& g,
                             const GeoReference& geo);

// The tracks alone (layer "track" features), as missionToGeoJson.
std::string tracksToGeoJson(const std::vector<Track>& tracks, const GridGeometry& g,
                            const GeoReference& geo);

}  // namespace rover::maps
