#pragma once
// Keep-out zones (issue 13; QGroundControl's geofence, MMGIS's draw tool): polygons in the local
// frame (metres from the map's lower-left corner, like rover starts) that an operator forbids.
// Every planner reads them from PlanningProblem::keepOut and applies them where its own validity
// rule lives:
// - coverage: a coverage cell any part of which lies in a zone is an obstacle (addKeepOut in
//   core/coverage/world.hpp). Any part, not the centre: visiting a cell means covering all of it,
//   and a move between two free cells stays inside those two cells, so no path crosses a zone.
// - team: a map cell a zone overlaps gets the class KeepOut, one that lies within the margin of a
//   zone Impassable (zonedClasses below); the traversal lattice, its reachability flood, RRT*
//   validity, the slot goals and the hybrid's footprint grids all read these classes, and the
//   coordinator refuses a simulated try with a sample on a KeepOut cell. A search cell whose
//   centre lies in a zone, or whose map cells are mostly zoned, is never a target.
// The one rasterisation is polygonCells (core/grid/geometry.hpp).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/grid/geometry.hpp"
#include "core/grid/raster.hpp"

namespace rover {

struct KeepOut {
  std::vector<Polygon> zones;

  bool empty() const { return zones.empty(); }
  // The first zone strictly holding `p`, or -1.
  int zoneAt(const Eigen::Vector2d& p) const;
  // The first zone that overlaps cell `c` of `g` (with positive area, cells grown by `grow`), or -1.
  int zoneOverlapping(const GridGeometry& g, CellIndex c, double grow = 0) const;
  // polygonCells of every zone on `g`.
  std::vector<std::uint8_t> cells(const GridGeometry& g, double grow = 0) const {
    return polygonCells(g, zones, grow);
  }
};

// `classes` (terrain::TerrainClass values) with the zones laid on: KeepOut where a zone overlaps
// the cell, Impassable where only the zone grown by `margin` metres does (so planned paths keep
// clear of the zone's edge, and a rover that ends there may still drive off it, as off any
// impassable spot). Returns the number of cells that were passable before.
std::int64_t applyKeepOut(Raster<std::uint8_t>& classes, const KeepOut& keepOut, double margin);

}  // namespace rover
