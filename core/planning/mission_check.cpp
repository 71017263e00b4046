#include "core/planning/mission_check.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/common/error.hpp"
#include "core/planning/departure.hpp"
#include "core/terrain/layers.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::planning {

namespace {

std::string metres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// The first rover with no way out (departureOrder), over ground on the map, on data and not
// impassable.
void refuseBoxedIn(const MissionGround& ground, const std::vector<RoverStart>& rovers, double safety) {
  std::vector<Eigen::Vector2d> starts;
  for (const auto& r : rovers) starts.push_back(r.position);
  const PassableGround passable = ground.dem ? passableGround(*ground.dem, ground.classes) : PassableGround{};
  const Departure d = departureOrder(starts, safety, passable);
  if (d.boxedIn.empty()) return;
  const std::string field = "rovers[" + std::to_string(d.boxedIn.front()) + "]";
  throw Error(ErrorCode::InvalidInput, field,
              field + ": start is boxed in: no way out keeping " + metres(safety + kDepartureMargin) +
                  " m (safety distance + " + metres(kDepartureMargin) +
                  " m) from the other rovers' starts over passable ground, even after the others have left");
}

}  // namespace

PassableGround passableGround(const terrain::Dem& dem, const Raster<std::uint8_t>* classes) {
  return [&dem, classes](const Eigen::Vector2d& p) {
    const auto cell = localToCell(dem.geometry(), p);
    if (!cell || !dem.valid(cell->row, cell->col)) return false;
    return !classes || classes->at(dem.geometry().index(*cell)) !=
                           static_cast<std::uint8_t>(terrain::TerrainClass::Impassable);
  };
}

void checkMissionStarts(const MissionGround& ground, const std::vector<RoverStart>& rovers,
                        const StartRules& rules) {
  checkRoverCount(rovers.size());
  const GridGeometry* map = ground.dem    ? &ground.dem->geometry()
                            : ground.grid ? &ground.grid->geometry()
                                          : nullptr;
  if (!map) throw Error(ErrorCode::InvalidInput, "map", "the mission has no map");
  // Cell sizes divide every position below: a NaN one would make cells out of nothing.
  if (ground.dem) checkGridGeometry(ground.dem->geometry(), "map");
  if (ground.grid) checkGridGeometry(ground.grid->geometry(), "map");
  std::vector<int> gridCells;
  for (std::size_t k = 0; k < rovers.size(); ++k) {
    const std::string field = "rovers[" + std::to_string(k) + "]";
    auto refuse = [&](const std::string& why) {
      throw Error(ErrorCode::InvalidInput, field, field + ": " + why);
    };
    const RoverStart& s = rovers[k];
    if (!s.position.allFinite() || !std::isfinite(s.heading))
      refuse("start must be finite numbers");
    auto cell = localToCell(*map, s.position);
    if (!cell)
      refuse("start (" + metres(s.position.x()) + ", " + metres(s.position.y()) +
             ") m is outside the map (" + metres(map->widthMetres()) + " × " +
             metres(map->heightMetres()) + " m)");
    if (ground.keepOut && !ground.keepOut->empty()) {
      const KeepOut& k = *ground.keepOut;
      if (int z = k.zoneAt(s.position); z >= 0)
        refuse("start is inside keep-out zone " + std::to_string(z));
      if (int z = k.zoneOverlapping(*map, *cell); z >= 0)
        refuse("start is on a map cell keep-out zone " + std::to_string(z) +
               " overlaps (a rover never stands on one)");
      if (ground.grid) {
        const GridGeometry& g = ground.grid->geometry();
        if (auto c = localToCell(g, s.position))
          if (int z = k.zoneOverlapping(g, *c); z >= 0)
            refuse("start is in a coverage cell keep-out zone " + std::to_string(z) + " overlaps");
      }
    }
    if (ground.dem) {
      if (!ground.dem->valid(cell->row, cell->col)) refuse("start is on nodata");
      if (!terrain::surfaceAt(*ground.dem, s.position.x(), s.position.y()))
        refuse("start is next to nodata");
      if (ground.classes && ground.classes->at(map->index(*cell)) ==
                                static_cast<std::uint8_t>(terrain::TerrainClass::Impassable))
        refuse("start is on impassable ground (a slope of " + metres(ground.impassableDeg) +
               "° or more)");
    }
    int gridCell = -1;
    if (ground.grid) {
      const GridGeometry& g = ground.grid->geometry();
      auto c = localToCell(g, s.position);
      // A DEM's coverage grid may leave a strip under a cell wide along the north and east edges.
      if (!c)
        refuse("start is outside the coverage grid (" + metres(g.widthMetres()) + " × " +
               metres(g.heightMetres()) + " m from the south-west corner)");
      gridCell = g.index(*c);
      if (ground.grid->isObstacle(gridCell))
        refuse(ground.dem ? "start is in a coverage cell that holds impassable ground or nodata"
                          : "start is on an obstacle");
    }
    for (std::size_t j = 0; j < k; ++j) {
      const std::string other = "rovers[" + std::to_string(j) + "]";
      if (rules.distinctCells && gridCell >= 0 && gridCells[j] == gridCell)
        refuse("start is in the same coverage cell as " + other);
      const double d = (rovers[j].position - s.position).norm();
      if (d < rules.safetyDistance)
        refuse("start is " + metres(d) + " m from " + other +
               ", closer than the safety distance of " + metres(rules.safetyDistance) + " m");
    }
    gridCells.push_back(gridCell);
  }
  if (rules.wayOut) refuseBoxedIn(ground, rovers, rules.safetyDistance);
}

}  // namespace rover::planning
