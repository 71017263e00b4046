// Terrain commands (issue: terrain layers): terrain, traversability, slope, layer, pdm, render.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/common/error.hpp"
#include "core/pdm/pdm.hpp"
#include "core/terrain/layers.hpp"
#include "maps/dem_io.hpp"
#include "maps/render.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/cli/arg_parser.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/dem_options.hpp"
#include "server/json/pdm_json.hpp"

namespace rover::cli {

namespace {

void addThresholdOptions(ArgParser& a) {
  a.option("high-risk", "DEG", "10", "Worst neighbour slope from which a cell is high risk.");
  a.option("impassable", "DEG", "15", "Worst neighbour slope from which a cell is impassable.");
}

terrain::TraversabilityParams readThresholds(const ArgParser& a) {
  terrain::TraversabilityParams p;
  p.highRiskDeg = a.real("high-risk", p.highRiskDeg, 0.01, 89.0);
  p.impassableDeg = a.real("impassable", p.impassableDeg, 0.01, 89.9);
  if (p.highRiskDeg >= p.impassableDeg)
    throw UsageError("invalid value for --high-risk: must be below --impassable");
  return p;
}


void addPdmSourceOptions(ArgParser& a) { addPdmOptions(a, PdmOptionNames{}); }
Raster<float> readPdm(const ArgParser& a, const terrain::Dem& dem) {
  return readPdmOptions(a, dem, PdmOptionNames{});
}

bool helpOr(ArgParser& a, const std::vector<std::string>& argv, std::ostream& out) {
  if (a.parse(argv)) return false;
  out << a.help();
  return true;
}

}  // namespace

int terrainCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser a("terrain", "Generate synthetic terrain (the default map) as a georeferenced GeoTIFF.");
  a.option("preset", "moon|mars", "mars", "Terrain kind.");
  a.option("size", "N", "600", "Cells per side.");
  a.option("cell", "M", "0.25", "Cell size in metres.");
  a.option("seed", "S", "1", "Seed.");
  a.option("out", "FILE.tif", "", "Output GeoTIFF (required).");
  if (helpOr(a, argv, out)) return 0;
  if (!a.has("out")) throw UsageError("missing --out FILE.tif");
  maps::SyntheticTerrainParams p;
  p.preset = a.str("preset", p.preset);
  p.size = static_cast<int>(a.integer("size", p.size, 16, 16384));
  p.cellSize = a.real("cell", p.cellSize, 1e-3, 1000);
  p.seed = static_cast<std::uint64_t>(a.integer("seed", 1, 0, INT64_MAX));
  terrain::Dem dem = orUsage([&] { return maps::generateTerrain(p); });
  orUsage([&] { maps::writeGeoTiff(a.str("out", ""), dem.z); return 0; });
  out << "wrote " << a.str("out", "") << ": " << p.preset << " terrain, " << p.size << " x "
      << p.size << " cells of " << p.cellSize << " m, seed " << p.seed << "\n";
  return 0;
}

int traversabilityCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser a("traversability", "Traversability classes from a DEM (paper 001 §3.4): worst slope to "
                                "the 8 neighbours, traversable / high risk / impassable.");
  a.positional("IN", "A DEM in any format GDAL reads.");
  addDemOptions(a);
  addThresholdOptions(a);
  a.option("out", "CLASSES.tif", "", "Write the classes as a uint8 GeoTIFF with a colour table.");
  a.flag("json", "Print the result as one JSON object.");
  if (helpOr(a, argv, out)) return 0;
  const std::string in = a.positionals()[0];
  auto params = readThresholds(a);
  maps::LoadedDem loaded = loadDemOrFail(in, readDemOptions(a));
  terrain::Traversability t = orUsage([&] { return terrain::traversability(loaded.dem, params); });
  if (a.has("out")) orUsage([&] { maps::writeClassesGeoTiff(a.str("out", ""), t.classes); return 0; });
  const GridGeometry& g = loaded.dem.geometry();
  using TC = terrain::TerrainClass;
  if (a.isSet("json")) {
    nlohmann::json j{{"file", in},
                     {"driver", loaded.info.driver},
                     {"rows", g.rows},
                     {"cols", g.cols},
                     {"cell_size_m", g.cellWidth},
                     {"cell_height_m", g.cellHeight},
                     {"geographic", loaded.info.geographic},
                     {"crs", loaded.info.crsName},
                     {"min_height_m", loaded.info.minHeight},
                     {"max_height_m", loaded.info.maxHeight},
                     {"traversable_pct", t.shares.percent(TC::Traversable)},
                     {"high_risk_pct", t.shares.percent(TC::HighRisk)},
                     {"impassable_pct", t.shares.percent(TC::Impassable)},
                     {"nodata_pct", t.shares.percent(TC::NoData)},
                     {"high_risk_deg", params.highRiskDeg},
                     {"impassable_deg", params.impassableDeg}};
    if (a.has("out")) j["out"] = a.str("out", "");
    out << j.dump() << "\n";
  } else {
    out << std::fixed << std::setprecision(2) << in << " (" << loaded.info.driver << "): " << g.rows
        << " x " << g.cols << " cells of " << g.cellWidth << " x " << g.cellHeight << " m"
        << (loaded.info.geographic ? " (at the centre; geographic CRS)" : "") << "\n"
        << "traversable " << t.shares.percent(TC::Traversable) << " %   high risk "
        << t.shares.percent(TC::HighRisk) << " %   impassable " << t.shares.percent(TC::Impassable)
        << " %   nodata " << t.shares.percent(TC::NoData) << " %\n";
  }
  return 0;
}

int layerCommand(const std::vector<std::string>& argv, std::ostream& out, const std::string& fixed) {
  ArgParser a(fixed.empty() ? "layer" : fixed,
              fixed.empty() ? "Write one terrain layer of a DEM as a float32 GeoTIFF: elevation, slope "
                              "(Horn, degrees), aspect, hillshade, worst-slope (8-neighbour, degrees)."
                            : "Horn slope in degrees, as gdaldem slope, as a float32 GeoTIFF.");
  if (fixed.empty()) a.positional("LAYER", "elevation | slope | aspect | hillshade | worst-slope");
  a.positional("IN", "A DEM in any format GDAL reads.");
  addDemOptions(a);
  a.option("out", "FILE.tif", "", "Output GeoTIFF (required).");
  if (helpOr(a, argv, out)) return 0;
  const std::string layer = fixed.empty() ? a.positionals()[0] : fixed;
  const std::string in = a.positionals()[fixed.empty() ? 1 : 0];
  if (!a.has("out")) throw UsageError("missing --out FILE.tif");
  static const std::vector<std::string> known{"elevation", "slope", "aspect", "hillshade", "worst-slope"};
  if (std::find(known.begin(), known.end(), layer) == known.end())
    throw UsageError("unknown layer '" + layer + "' (elevation, slope, aspect, hillshade, worst-slope)");
  maps::LoadedDem loaded = loadDemOrFail(in, readDemOptions(a));
  Raster<float> r = layer == "elevation" ? loaded.dem.z
                    : layer == "slope"   ? terrain::slopeHorn(loaded.dem)
                    : layer == "aspect"  ? terrain::aspectHorn(loaded.dem)
                    : layer == "hillshade"
                        ? terrain::hillshade(loaded.dem)
                        : terrain::traversability(loaded.dem, {}, true).worstSlopeDeg;
  r.geo = loaded.dem.z.geo;
  orUsage([&] { maps::writeGeoTiff(a.str("out", ""), r); return 0; });
  out << "wrote " << a.str("out", "") << ": " << layer << ", " << r.geometry.rows << " x "
      << r.geometry.cols << " cells\n";
  return 0;
}

int pdmCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser a("pdm", "A probability distribution map (paper 001 eq. 5) on a DEM's grid, as probability "
                     "mass per cell summing to 1 over the cells with data.");
  a.positional("MAP", "The DEM whose grid the PDM covers.");
  addDemOptions(a);
  addPdmSourceOptions(a);
  a.option("out", "FILE.tif", "", "Output float32 GeoTIFF (required).");
  if (helpOr(a, argv, out)) return 0;
  if (!a.has("out")) throw UsageError("missing --out FILE.tif");
  maps::LoadedDem loaded = loadDemOrFail(a.positionals()[0], readDemOptions(a));
  Raster<float> p = readPdm(a, loaded.dem);
  orUsage([&] { maps::writeGeoTiff(a.str("out", ""), p); return 0; });
  double total = 0, peak = 0;
  for (int i = 0; i < p.geometry.cellCount(); ++i) total += p.at(i), peak = std::max<double>(peak, p.at(i));
  out << "wrote " << a.str("out", "") << ": " << p.geometry.rows << " x " << p.geometry.cols
      << " cells, total mass " << total << ", peak cell " << peak << "\n";
  return 0;
}

int renderCommand(const std::vector<std::string>& argv, std::ostream& out) {
  ArgParser a("render", "A colourised PNG of a terrain layer with a legend.");
  a.positional("LAYER", "elevation | hillshade | slope | traversability | pdm");
  a.positional("IN", "A DEM in any format GDAL reads.");
  addDemOptions(a);
  addPdmSourceOptions(a);
  addThresholdOptions(a);
  a.option("max", "N", "0", "Downsample so neither side exceeds N pixels (0 = full size).");
  a.flag("no-legend", "Leave the legend out.");
  a.option("out", "FILE.png", "", "Output PNG (required).");
  if (helpOr(a, argv, out)) return 0;
  if (!a.has("out")) throw UsageError("missing --out FILE.png");
  maps::RenderLayer layer = orUsage([&] { return maps::renderLayerFromName(a.positionals()[0]); });
  maps::LoadedDem loaded = loadDemOrFail(a.positionals()[1], readDemOptions(a));
  const terrain::Dem& dem = loaded.dem;
  maps::RenderInput input;
  input.dem = &dem;
  Raster<float> shade, slope, pdmRaster;
  Raster<std::uint8_t> classes;
  if (layer == maps::RenderLayer::Elevation || layer == maps::RenderLayer::Hillshade) {
    shade = terrain::hillshade(dem);
    input.hillshade = &shade;
  } else if (layer == maps::RenderLayer::Slope) {
    slope = terrain::slopeHorn(dem);
    input.slopeDeg = &slope;
  } else if (layer == maps::RenderLayer::Traversability) {
    classes = terrain::traversability(dem, readThresholds(a)).classes;
    input.classes = &classes;
  } else {
    pdmRaster = readPdm(a, dem);
    input.pdm = &pdmRaster;
  }
  maps::RenderOptions ro;
  ro.maxSize = static_cast<int>(a.integer("max", 0, 0, 65536));
  ro.legend = !a.isSet("no-legend");
  auto png = orUsage([&] { return maps::encodePng(maps::renderLayer(layer, input, ro)); });
  const std::string path = a.str("out", "");
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  if (!f) throw UsageError(path + ": cannot write");
  out << "wrote " << path << " (" << png.size() << " bytes)\n";
  return 0;
}

}  // namespace rover::cli
