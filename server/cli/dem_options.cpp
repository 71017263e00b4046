#include "server/cli/dem_options.hpp"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/common/error.hpp"
#include "core/pdm/pdm.hpp"
#include "server/json/pdm_json.hpp"
#include "server/problems/problem_builder.hpp"

namespace rover::cli {

namespace {
std::string kebab(std::string key) {
  for (char& c : key)
    if (c == '_') c = '-';
  return key;
}
}  // namespace

// The DEM options come from the import table (maps/dem_import_options) that the upload route also
// reads, so --crop, --crop-px, --vertical-scale and --body take what ?crop= ... take.
void addDemOptions(ArgParser& a, const std::string& cellOption, const std::string& cellDefault) {
  for (const auto& info : maps::demImportOptionInfos()) {
    if (info.key == "cell") a.option(cellOption, info.metavar, cellDefault, info.doc);
    else a.option(kebab(info.key), info.metavar, info.key == "vertical_scale" ? "1" : info.key == "body" ? "auto" : "", info.doc);
  }
  a.option("resampling", "ALG", "auto", "auto | near | average | bilinear | cubic.");
  a.option("max-cells", "N", "200000000", "Refuse rasters larger than N cells (checked before reading).");
}

maps::DemImport readDemImport(const ArgParser& a, const std::string& cellOption) {
  std::map<std::string, std::string> values;
  for (const auto& info : maps::demImportOptionInfos()) {
    const std::string option = info.key == "cell" ? cellOption : kebab(info.key);
    if (a.has(option)) values[info.key] = a.str(option, "");
  }
  maps::DemImport d;
  try {
    d = maps::parseDemImportOptions(values);
  } catch (const Error& e) {
    const std::string option = e.field() == "cell" ? cellOption : kebab(e.field());
    throw UsageError("invalid value for --" + option + ": " + e.what());
  }
  d.load.resampling = a.str("resampling", "auto");
  d.load.maxCells = a.integer("max-cells", d.load.maxCells, 4, INT64_MAX);
  return d;
}

maps::LoadOptions readDemOptions(const ArgParser& a, const std::string& cellOption, double cellDefault) {
  maps::LoadOptions o = readDemImport(a, cellOption).load;
  if (!a.has(cellOption)) o.cellSize = cellDefault;
  return o;
}

maps::LoadedDem loadDemOrFail(const std::string& path, const maps::LoadOptions& options) {
  try {
    return maps::loadDem(path, options);
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
}

namespace {


std::vector<std::uint8_t> validMask(const terrain::Dem& dem) {
  std::vector<std::uint8_t> m(dem.geometry().cellCount());
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = !std::isnan(dem.z.at(static_cast<int>(i)));
  return m;
}

}  // namespace

void addPdmOptions(ArgParser& a, const PdmOptionNames& n) {
  a.option(n.gaussians, "FILE.json", "", "PDM: Gaussian components {\"components\":[{x,y,sigma_x,"
                                         "sigma_y,rotation_deg,weight}]} in the local frame (metres).");
  a.option(n.random, "G", "", "PDM: G random Gaussian components (paper 001: G = 4).");
  if (n.seed != "seed") a.option(n.seed, "S", "the --seed", "Seed for --" + n.random + ".");
  else a.option("seed", "S", "1", "Seed for --" + n.random + ".");
  a.option(n.raster, "FILE", "", "PDM: a raster of non-negative weights, resampled onto the map's grid.");
}

Raster<float> readPdmOptions(const ArgParser& a, const terrain::Dem& dem, const PdmOptionNames& n,
                             bool optional, const PdmArea* area) {
  const int sources = a.has(n.gaussians) + a.has(n.random) + a.has(n.raster);
  if (sources == 0 && optional) return {};
  if (sources != 1)
    throw UsageError("give exactly one of --" + n.gaussians + ", --" + n.random + ", --" + n.raster);
  const GridGeometry& g = dem.geometry();
  auto valid = validMask(dem);
  if (area)
    for (std::size_t i = 0; i < valid.size(); ++i) valid[i] = valid[i] && area->inArea[i];
  if (a.has(n.random)) {
    int count = static_cast<int>(a.integer(n.random, 4, 1, 1000));
    const std::string seedOption = a.has(n.seed) ? n.seed : "seed";
    auto seed = static_cast<std::uint64_t>(a.integer(seedOption, 1, 0, INT64_MAX));
    if (!area) return orUsage([&] { return problems::randomPdm(dem, count, seed); });
    Raster<float> p = orUsage([&] { return pdm::discretise(pdm::randomGaussians(g, count, seed), g, valid); });
    p.geo = dem.z.geo;
    return p;
  }
  if (a.has(n.gaussians)) {
    const std::string path = a.str(n.gaussians, "");
    std::ifstream in(path);
    if (!in) throw UsageError(path + ": cannot open");
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded()) throw UsageError(path + ": not valid JSON");
    Raster<float> p = orUsage([&] {
      const auto components = json::gaussiansFromJson(j);
      return area ? pdm::discretiseOnWindow(components, area->map, g, area->window.origin, valid)
                  : pdm::discretise(components, g, valid);
    });
    p.geo = dem.z.geo;
    return p;
  }
  // A weight raster on the map's grid: warp it onto the DEM's extent and cell size.
  maps::LoadOptions o;
  if (dem.z.geo.valid) {
    const auto& gt = dem.z.geo.geotransform;
    o.crop = std::array<double, 4>{gt[0], gt[3] + g.rows * gt[5], g.cols * gt[1], -g.rows * gt[5]};
  }
  const std::string path = a.str(n.raster, "");
  maps::LoadedDem w = loadDemOrFail(path, o);
  if (w.dem.geometry().rows != g.rows || w.dem.geometry().cols != g.cols)
    throw UsageError(path + ": the PDM raster does not cover the map on its grid (" +
                     std::to_string(w.dem.geometry().rows) + " x " +
                     std::to_string(w.dem.geometry().cols) + " cells)");
  Raster<float> p = orUsage([&] { return pdm::normaliseWeights(w.dem.z, valid); });
  p.geo = dem.z.geo;
  return p;
}

}  // namespace rover::cli
