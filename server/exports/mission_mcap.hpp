#pragma once
// A mission's replay as an MCAP file (issue 28) that Foxglove and Lichtblick open: Foxglove's
// well-known schemas in JSON encoding (schema encoding "jsonschema", message encoding "json"),
// everything in frame "map" = the map's local frame (SPEC §0: metres east/north of the
// lower-left corner), z = 0 (a plan view over the flat terrain grid; heights are telemetry).
//
// Channels, in id order:
//   /map/terrain        foxglove.Grid         one message at t = 0: elevation (float32, NaN =
//                                             nodata), block means of the DEM downsampled so the
//                                             grid has at most kMaxTerrainCells cells
//   /map/scene          foxglove.SceneUpdate  one message at t = 0: the team route (line), route
//                                             targets (spheres), each rover's planned path and any
//                                             other overlay (lines), keep-out zones (line loops)
//   /incidents          foxglove.Log          one message per incident, at its time
//   per rover K, from 0:
//   /rover_K/pose       foxglove.PoseInFrame  one per trajectory sample: position, yaw (heading)
//                                             as a quaternion about z
//   /rover_K/fix        foxglove.LocationFix  the same samples as latitude/longitude in degrees on
//                                             the map's body (maps/lon_lat.hpp); only when the
//                                             map has a CRS PROJ can unproject
//   /rover_K/telemetry  roverplan.RoverTelemetry (our jsonschema) the same samples: pitch, roll,
//                                             heading (deg), speed (m/s), energy used so far (J),
//                                             terrain elevation (m); a quantity the planner does
//                                             not know is left out of the message
// Time: the mission clock, log_time = publish_time = seconds since the mission start in ns. A
// planner without a clock (coverage: grid moves) plays one move a second (move i at i s;
// incidents at their step). Samples: a team mission's 10 Hz simulator samples (Track::samples);
// coverage's path points with heading, attitude and height from the DEM (groundSample).
// A pure function of the result, the DEM and the zones: the same inputs give the same bytes.
// Memory besides the writer's one chunk (~1 MB): 16 bytes a sample or incident for the merge into
// time order (the default team mission: 110 k samples, 1.8 MB), the terrain grid's float32 copy
// and its base64 text (at most 4 + 5.6 MB), and for coverage the derived samples (80 bytes a
// point); the samples of a planner with a clock are read in place.
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "core/planning/keep_out.hpp"
#include "core/planning/plan_result.hpp"
#include "core/terrain/dem.hpp"
#include "maps/geojson.hpp"
#include "server/exports/mcap_writer.hpp"

namespace rover::exports {

// The terrain grid's cap: 1024 × 1024 cells (4 MiB of float32, 5.6 MB as base64 JSON).
constexpr std::int64_t kMaxTerrainCells = 1 << 20;

struct ReplayInput {
  const PlanResult* result = nullptr;
  const terrain::Dem* dem = nullptr;  // null: no terrain grid, no heights, no fixes
  // Where the DEM's lower-left corner lies in the map's frame: a mission area's window is a part
  // of the map (its heights are read, and its terrain grid placed, there); 0 for the whole map.
  Eigen::Vector2d demOrigin{0, 0};
  GridGeometry grid;                  // the map's grid (the local frame of the tracks)
  GeoReference geo;                   // the map's georeference ("" CRS: no fixes)
  std::vector<maps::Zone> zones;      // keep-out zones in the local frame
  std::vector<double> startHeadings;  // coverage: each rover's start heading (rad)
};

// Keep-out zones of a problem as the exports take them (unnamed), moved by `by` (a mission
// area's window origin: the window's frame → the map's).
std::vector<maps::Zone> zonesOf(const KeepOut& keepOut, const Eigen::Vector2d& by = {0, 0});

// The block size (DEM cells a side) the terrain grid is averaged over: the smallest f with
// ceil(rows/f)·ceil(cols/f) <= kMaxTerrainCells.
int terrainStride(int rows, int cols);

// Writes the replay to `out`; returns what was written. Throws std::runtime_error on a failed
// stream.
McapTotals writeReplayMcap(const ReplayInput& in, std::ostream& out);
// The same to `path` (created or truncated); throws std::runtime_error naming no path when the
// file cannot be written.
McapTotals writeReplayMcapFile(const ReplayInput& in, const std::string& path);

}  // namespace rover::exports
