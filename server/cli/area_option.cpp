#include "server/cli/area_option.hpp"

#include "server/cli/dem_options.hpp"
#include "server/json/area_json.hpp"

namespace rover::cli {

void addAreaOption(ArgParser& a) {
  a.option("area", "X0,Y0,X1,Y1", "the whole DEM",
           "Plan in this rectangle of the DEM (metres in its local frame, from its lower-left corner) at "
           "its own resolution: only the area and a margin of " +
               std::to_string(kAreaMarginCells) +
               " cells are read and analysed; ground outside the area is keep-out. At most 4096 x 4096 "
               "cells with the margin.");
}

AreaDem loadDemInArea(const ArgParser& a, const std::string& path, const maps::DemImport& import,
                      const std::string& cellOption) {
  AreaDem out;
  if (!a.has("area")) {
    out.loaded = loadDemOrFail(path, import.load);
    out.window = wholeMap(out.loaded.dem.geometry());
    out.mapGrid = out.loaded.dem.geometry();
    out.mapGeo = out.loaded.dem.z.geo;
    return out;
  }
  if (import.load.cellSize > 0 || import.load.crop || import.load.cropPixels)
    throw UsageError("--area plans at the DEM's own resolution in its own frame: give it without --" + cellOption +
                     ", --crop and --crop-px (or cut the DEM first with gdal_translate)");
  const std::vector<double> c = a.realList("area");
  if (c.size() != 4) throw UsageError("invalid value for --area: give X0,Y0,X1,Y1 in metres");
  const maps::DemHeader header = orUsage([&] { return maps::readDemHeader(path); });
  const MissionArea area = rectangleArea(c[0], c[1], c[2], c[3]);
  try {
    checkMissionArea(area, header.geometry);
  } catch (const Error& e) {
    throw UsageError(std::string("invalid value for --area: ") + e.what());
  }
  out.area = area;
  out.window = planningWindow(header.geometry, area);
  out.mapGrid = header.geometry;
  out.mapGeo = header.geo;
  const PlanningWindow& w = out.window;
  out.loaded = orUsage([&] {
    return maps::loadDemWindow(path, w.row0, w.col0, w.grid.rows, w.grid.cols, import.load.verticalScale);
  });
  return out;
}

nlohmann::json areaJson(const AreaDem& dem) {
  return {{"area", dem.area ? json::areaToJson(*dem.area) : nlohmann::json(nullptr)},
          {"planning_window", json::windowToJson(dem.window)}};
}

}  // namespace rover::cli
