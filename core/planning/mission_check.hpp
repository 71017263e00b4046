#pragma once
// One check of a mission's rover starts for every planner (issue 11), so the coverage and the team
// planners, the server and the CLI say the same thing for the same start: a start outside the map,
// on nodata or next to it, or on impassable ground is refused, and so are two rovers too close.
// Pure: it reads the map it is given and throws rover::Error (InvalidInput, field "rovers[K]").
#include <cstdint>
#include <vector>

#include "core/coverage/world.hpp"
#include "core/grid/raster.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/keep_out.hpp"
#include "core/planning/planner.hpp"
#include "core/terrain/dem.hpp"

namespace rover::planning {

// The ground under the starts. `dem` + `classes` is the map at its own resolution (the team
// planners plan on it; the coverage planner's grid is built from it); `grid` is the coverage
// grid, when the planner uses one (a random world has a grid and no DEM).
struct MissionGround {
  const terrain::Dem* dem = nullptr;
  const Raster<std::uint8_t>* classes = nullptr;  // terrain::TerrainClass per DEM cell
  double impassableDeg = 15.0;                    // the threshold the classes used (for messages)
  const coverage::World* grid = nullptr;
  // The operator's keep-out zones (null or empty: none). A start inside one, or on a map cell or
  // coverage cell one overlaps, is refused: a rover never stands on a cell a zone touches.
  const KeepOut* keepOut = nullptr;
};

// Ground a rover may drive over on the map: on the DEM, on data and (with `classes`) not
// impassable. The one rule the start check and the generated formation's way-out test share.
PassableGround passableGround(const terrain::Dem& dem, const Raster<std::uint8_t>* classes);

struct StartRules {
  // Two starts closer than this (metres) are refused: the team planners' safety distance.
  double safetyDistance = 0.0;
  // Two starts in one cell of the coverage grid are refused: coverage rovers never share a cell.
  bool distinctCells = false;
  // A rover that cannot leave its start keeping the safety distance, past the rovers standing at
  // theirs and over ground that is not impassable, even after every rover that can leave has
  // (departure.hpp), is refused: the team planners keep every standing rover clear (issue 25).
  bool wayOut = false;
};

// Throws for the first start that breaks a rule, naming it rovers[K]; "rovers" for a count
// outside 1..64. Checks, in order: finite numbers; inside the map; on data, with data all round
// (the bilinear surface a rover stands on); out of the keep-out zones; not impassable; the coverage cell not an obstacle;
// apart from every earlier start; with `wayOut`, a way out (the first rover without one named).
void checkMissionStarts(const MissionGround& ground, const std::vector<RoverStart>& rovers,
                        const StartRules& rules);

}  // namespace rover::planning
