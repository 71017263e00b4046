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

std::string tracksToGeoJson(const std::vector<Track>& tracks, const GridGeometry& g,
                            const GeoReference& geo);

}  // namespace rover::maps
