#include "server/api/map_catalog.hpp"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <set>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/render.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/http/http_types.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

std::string safeName(const std::string& name, const std::string& fallback) {
  std::string base = fs::path(name).filename().string(), out;
  for (char c : base) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  if (out.empty() || out == "." || out == "..") out = fallback;
  return out;
}

bool opensAsRaster(const std::string& path) {
  maps::ensureGdal();
  GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  if (!ds) return false;
  bool ok = GDALGetRasterCount(ds) > 0;
  GDALClose(ds);
  return ok;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The file GDAL should open among the ones given: a PDS3 label first, else the first raster.
std::string pickRaster(const std::vector<std::string>& candidates) {
  for (const auto& c : candidates)
    if (lower(fs::path(c).extension().string()) == ".lbl" && opensAsRaster(c)) return c;
  for (const auto& c : candidates) {
    std::string ext = lower(fs::path(c).extension().string());
    if (ext == ".hdr" || ext == ".xml" || ext == ".aux" || ext == ".txt" || ext == ".prj") continue;
    if (opensAsRaster(c)) return c;
  }
  for (const auto& c : candidates)  // PDS4 (.xml labels) and anything else GDAL opens
    if (opensAsRaster(c)) return c;
  return "";
}

std::vector<std::string> zipMembers(const std::string& zipPath) {
  std::vector<std::string> out;
  const std::string root = "/vsizip/" + zipPath;
  char** list = VSIReadDirRecursive(root.c_str());
  for (char** p = list; p && *p; ++p) {
    std::string member = root + "/" + *p;
    VSIStatBufL st;
    if (VSIStatL(member.c_str(), &st) == 0 && !VSI_ISDIR(st.st_mode)) out.push_back(member);
  }
  CSLDestroy(list);
  std::sort(out.begin(), out.end());
  return out;
}

nlohmann::json metaFor(const maps::LoadedDem& d, const terrain::Traversability& t,
                       const std::vector<std::string>& sources) {
  const GridGeometry& g = d.dem.geometry();
  using TC = terrain::TerrainClass;
  return {{"rows", g.rows},
          {"cols", g.cols},
          {"cell_size_m", g.cellWidth},
          {"cell_height_m", g.cellHeight},
          {"width_m", g.widthMetres()},
          {"height_m", g.heightMetres()},
          {"crs", d.info.crsName},
          {"geographic", d.info.geographic},
          {"driver", d.info.driver},
          {"source_files", sources},
          {"resampling", d.info.resampling},
          {"elevation", {{"min", d.info.minHeight}, {"max", d.info.maxHeight}}},
          {"classes",
           {{"traversable_pct", t.shares.percent(TC::Traversable)},
            {"high_risk_pct", t.shares.percent(TC::HighRisk)},
            {"impassable_pct", t.shares.percent(TC::Impassable)},
            {"nodata_pct", t.shares.percent(TC::NoData)}}}};
}

}  // namespace

MapCatalog::MapCatalog(store::Database& db, store::DataDir& dir, std::int64_t maxCells)
    : db_(db), dir_(dir), maxCells_(maxCells) {}

store::MapRecord MapCatalog::importDem(const std::vector<UploadedFile>& files, const std::string& name,
                                       double cellSize) {
  if (files.empty()) throw ApiError(400, "invalid_input", "no DEM file in the request", "file");
  if (!(cellSize >= 0) || !std::isfinite(cellSize) || cellSize > 1e5)
    throw ApiError(400, "invalid_parameter", "cell must be a positive number of metres", "cell");
  if (name.size() > 200) throw ApiError(400, "invalid_parameter", "name is longer than 200 characters", "name");
  const std::string staging = dir_.stagingDir();
  try {
    std::vector<std::string> sources, candidates;
    for (std::size_t i = 0; i < files.size(); ++i) {
      std::string fallback = "upload";
      fallback += std::to_string(i);
      std::string fname = safeName(files[i].filename, fallback);
      if (std::find(sources.begin(), sources.end(), fname) != sources.end()) {
        std::string unique = std::to_string(i);
        unique += '_';
        fname = unique + fname;
      }
      const std::string target = (fs::path(staging) / fname).string();
      fs::rename(files[i].path, target);
      sources.push_back(fname);
      if (lower(fs::path(fname).extension().string()) == ".zip") {
        auto members = zipMembers(target);
        candidates.insert(candidates.end(), members.begin(), members.end());
      } else {
        candidates.push_back(target);
      }
    }
    const std::string raster = pickRaster(candidates);
    if (raster.empty())
      throw ApiError(400, "invalid_dem",
                     "no raster GDAL can read in the upload (" + std::to_string(files.size()) + " file(s))", "file");
    maps::LoadOptions o;
    o.cellSize = cellSize;
    o.maxCells = maxCells_;
    maps::LoadedDem d;
    try {
      d = maps::loadDem(raster, o);
    } catch (const Error& e) {
      std::string msg = e.what();
      // Report the client's file name, not our staging path.
      if (msg.rfind(raster, 0) == 0) msg = fs::path(raster).filename().string() + msg.substr(raster.size());
      throw ApiError(400, e.field() == "max_cells" ? "too_large" : "invalid_dem", msg,
                     e.field() == "max_cells" ? "file" : e.field());
    }
    terrain::Traversability t = terrain::traversability(d.dem);
    maps::writeGeoTiff((fs::path(staging) / "dem.tif").string(), d.dem.z);
    store::MapRecord rec;
    rec.id = store::DataDir::newId();
    rec.name = name.empty() ? fs::path(raster).filename().string() : name;
    rec.createdAt = store::nowIso();
    rec.meta = metaFor(d, t, sources);
    // Files first, then the row: a crash in between leaves an orphan folder nobody lists.
    dir_.commitDir(staging, dir_.mapDir(rec.id));
    db_.insertMap(rec);
    return rec;
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
}

int MapCatalog::sweepOrphans() {
  std::set<std::string> maps, pdms;
  for (const auto& m : db_.listMaps()) {
    maps.insert(m.id);
    for (const auto& p : db_.listPdms(m.id)) pdms.insert(p.id);
  }
  int removed = 0;
  auto sweep = [&](const std::string& parent, const std::set<std::string>& keep) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(parent, ec)) {
      if (!e.is_directory() || keep.count(e.path().filename().string())) continue;
      store::DataDir::removeTree(e.path().string());
      ++removed;
    }
  };
  sweep(fs::path(dir_.mapDir("x")).parent_path().string(), maps);
  sweep(fs::path(dir_.pdmDir("x")).parent_path().string(), pdms);
  return removed;
}

void MapCatalog::ensureDefaultMap() {
  if (!db_.listMaps().empty()) return;
  maps::SyntheticTerrainParams p;  // mars, 600 × 600 × 0.25 m, seed 1
  terrain::Dem dem = maps::generateTerrain(p);
  const std::string staging = dir_.stagingDir();
  const std::string path = (fs::path(staging) / "default-mars.tif").string();
  maps::writeGeoTiff(path, dem.z);
  const std::string moved = (fs::path(dir_.tmpDir()) / (store::DataDir::newId() + ".tif")).string();
  fs::rename(path, moved);
  store::DataDir::removeTree(staging);
  importDem({{moved, "default-mars.tif"}}, "Default: synthetic Mars, 150 m (seed 1)", 0);
}

std::shared_ptr<const MapData> MapCatalog::loadFromDisk(const store::MapRecord& r) {
  auto data = std::make_shared<MapData>();
  data->record = r;
  data->dem = maps::loadDem((fs::path(dir_.mapDir(r.id)) / "dem.tif").string()).dem;
  data->traversability = terrain::traversability(data->dem);
  data->valid.resize(data->dem.geometry().cellCount());
  for (int i = 0; i < data->dem.geometry().cellCount(); ++i) data->valid[i] = !std::isnan(data->dem.z.at(i));
  return data;
}

std::shared_ptr<const MapData> MapCatalog::get(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    for (auto it = cache_.begin(); it != cache_.end(); ++it)
      if ((*it)->record.id == id) {
        cache_.splice(cache_.begin(), cache_, it);
        return cache_.front();
      }
  }
  auto rec = db_.getMap(id);
  if (!rec) throw ApiError(404, "not_found", "no map '" + id + "'", "id");
  auto data = loadFromDisk(*rec);
  std::lock_guard lock(mutex_);
  cache_.push_front(data);
  if (cache_.size() > 4) cache_.pop_back();
  return data;
}

void MapCatalog::remove(const std::string& id) {
  auto pdms = db_.listPdms(id);
  if (!db_.deleteMap(id)) throw ApiError(404, "not_found", "no map '" + id + "'", "id");
  {
    std::lock_guard lock(mutex_);
    cache_.remove_if([&](const auto& m) { return m->record.id == id; });
    cellCache_.remove_if([&](const auto& e) { return e.first.rfind(id + "@", 0) == 0; });
  }
  for (const auto& p : pdms) store::DataDir::removeTree(dir_.pdmDir(p.id));
  store::DataDir::removeTree(dir_.mapDir(id));
}

std::shared_ptr<const terrain::Dem> MapCatalog::demAtCell(const std::string& id, double cellSize) {
  auto map = get(id);
  if (cellSize <= 0 || std::fabs(cellSize - map->dem.geometry().cellWidth) < 1e-9)
    return std::shared_ptr<const terrain::Dem>(map, &map->dem);
  const std::string key = id + "@" + std::to_string(cellSize);
  {
    std::lock_guard lock(mutex_);
    for (auto& e : cellCache_)
      if (e.first == key) return e.second;
  }
  maps::LoadOptions o;
  o.cellSize = cellSize;
  o.maxCells = maxCells_;
  std::shared_ptr<const terrain::Dem> dem;
  try {
    dem = std::make_shared<terrain::Dem>(maps::loadDem((fs::path(dir_.mapDir(id)) / "dem.tif").string(), o).dem);
  } catch (const Error& e) {
    throw ApiError(400, "invalid_parameter", std::string("coverage_cell: ") + e.what(), "params.coverage_cell");
  }
  std::lock_guard lock(mutex_);
  cellCache_.emplace_front(key, dem);
  if (cellCache_.size() > 4) cellCache_.pop_back();
  return dem;
}

std::string MapCatalog::layerFile(const std::string& id, const std::string& layer,
                                  const std::string& format, int max, const std::string& pdmId) {
  static const std::vector<std::string> layers{"elevation", "hillshade", "slope", "traversability", "pdm"};
  if (std::find(layers.begin(), layers.end(), layer) == layers.end())
    throw ApiError(404, "not_found", "no layer '" + layer + "' (elevation, hillshade, slope, traversability, pdm)", "layer");
  if (format != "png" && format != "tif" && format != "f32")
    throw ApiError(404, "not_found", "no format '" + format + "' (png, tif, f32)", "format");
  if (max < 0 || max > 16384) throw ApiError(400, "invalid_parameter", "max must be in [0, 16384]", "max");
  auto map = get(id);
  std::string pdm = pdmId;
  if (layer == "pdm" && pdm.empty()) {
    auto list = db_.listPdms(id);
    if (list.empty()) throw ApiError(404, "not_found", "the map has no PDM yet", "pdm");
    pdm = list.back().id;
  }
  if (layer == "pdm") {
    auto rec = db_.getPdm(pdm);
    if (!rec || rec->mapId != id) throw ApiError(404, "not_found", "no PDM '" + pdm + "' on this map", "pdm");
  }
  const fs::path dir = fs::path(dir_.mapDir(id)) / "layers";
  std::string file = layer;
  if (layer == "pdm") file += "-" + pdm;
  if (format == "png" && max > 0) {
    file += '-';
    file += std::to_string(max);
  }
  file += '.';
  file += format;
  const fs::path path = dir / file;
  std::lock_guard lock(mutex_);
  if (fs::exists(path)) return path.string();
  fs::create_directories(dir);
  const terrain::Dem& dem = map->dem;
  Raster<float> values;
  if (layer == "elevation") values = dem.z;
  else if (layer == "hillshade") values = terrain::hillshade(dem);
  else if (layer == "slope") values = terrain::slopeHorn(dem);
  else if (layer == "pdm") values = maps::loadDem(pdmFile(pdm)).dem.z;
  values.geo = dem.z.geo;
  if (format == "tif") {
    if (layer == "traversability") maps::writeClassesGeoTiff(path.string(), map->traversability.classes);
    else maps::writeGeoTiff(path.string(), values);
  } else if (format == "f32") {
    std::string bytes;
    const int n = dem.geometry().cellCount();
    bytes.resize(4ull * n);
    for (int i = 0; i < n; ++i) {
      float v = layer == "traversability" ? static_cast<float>(map->traversability.classes.at(i)) : values.at(i);
      std::memcpy(&bytes[4ull * i], &v, 4);  // x86-64 and aarch64 are little-endian
    }
    store::DataDir::writeFileAtomic(path.string(), bytes);
  } else {
    maps::RenderInput in;
    in.dem = &dem;
    Raster<float> shade;
    if (layer == "elevation" || layer == "hillshade") {
      shade = layer == "hillshade" ? values : terrain::hillshade(dem);
      in.hillshade = &shade;
    }
    if (layer == "slope") in.slopeDeg = &values;
    if (layer == "traversability") in.classes = &map->traversability.classes;
    if (layer == "pdm") in.pdm = &values;
    maps::RenderOptions ro;
    ro.maxSize = max;
    auto png = maps::encodePng(maps::renderLayer(maps::renderLayerFromName(layer), in, ro));
    store::DataDir::writeFileAtomic(path.string(), std::string(png.begin(), png.end()));
  }
  return path.string();
}

std::string MapCatalog::pdmFile(const std::string& pdmId) const {
  return (fs::path(dir_.pdmDir(pdmId)) / "pdm.tif").string();
}

store::PdmRecord MapCatalog::createPdm(const std::string& mapId, const std::string& name,
                                       const std::vector<pdm::Gaussian>& components,
                                       const nlohmann::json& meta) {
  auto map = get(mapId);
  Raster<float> mass;
  try {
    mass = pdm::discretise(components, map->dem.geometry(), map->valid);
  } catch (const Error& e) {
    throw ApiError(400, "invalid_parameter", e.what(), e.field());
  }
  mass.geo = map->dem.z.geo;
  return storePdm(mapId, name.empty() ? "PDM " + store::nowIso() : name, mass, meta);
}

store::PdmRecord MapCatalog::storePdm(const std::string& mapId, const std::string& name,
                                      const Raster<float>& mass, const nlohmann::json& meta) {
  // Files first, then the row, as for maps.
  const std::string staging = dir_.stagingDir();
  try {
    maps::writeGeoTiff((fs::path(staging) / "pdm.tif").string(), mass);
    store::PdmRecord rec;
    rec.id = store::DataDir::newId();
    rec.mapId = mapId;
    rec.name = name;
    rec.createdAt = store::nowIso();
    rec.meta = meta;
    dir_.commitDir(staging, dir_.pdmDir(rec.id));
    db_.insertPdm(rec);
    return rec;
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
}

store::PdmRecord MapCatalog::createPdmFromRaster(const std::string& mapId, const std::string& name,
                                                 const std::string& rasterPath) {
  auto map = get(mapId);
  const GridGeometry& g = map->dem.geometry();
  maps::LoadOptions o;
  o.maxCells = maxCells_;
  const auto& gt = map->dem.z.geo.geotransform;
  if (map->dem.z.geo.valid && !map->record.meta.value("geographic", false))
    o.crop = std::array<double, 4>{gt[0], gt[3] + g.rows * gt[5], g.cols * gt[1], -g.rows * gt[5]};
  maps::LoadedDem w;
  try {
    w = maps::loadDem(rasterPath, o);
  } catch (const Error& e) {
    std::string msg = e.what();
    if (msg.rfind(rasterPath, 0) == 0) msg = "PDM raster" + msg.substr(rasterPath.size());
    throw ApiError(400, "invalid_pdm", msg, "file");
  }
  if (w.dem.geometry().rows != g.rows || w.dem.geometry().cols != g.cols)
    throw ApiError(400, "invalid_pdm",
                   "the PDM raster does not cover the map on its grid (" + std::to_string(w.dem.geometry().rows) +
                       " x " + std::to_string(w.dem.geometry().cols) + " cells, the map has " +
                       std::to_string(g.rows) + " x " + std::to_string(g.cols) + ")",
                   "file");
  Raster<float> mass;
  try {
    mass = pdm::normaliseWeights(w.dem.z, map->valid);
  } catch (const Error& e) {
    throw ApiError(400, "invalid_pdm", e.what(), "file");
  }
  mass.geo = map->dem.z.geo;
  return storePdm(mapId, name.empty() ? "raster PDM" : name, mass, {{"kind", "raster"}});
}

Raster<float> MapCatalog::pdmMass(const std::string& pdmId) {
  return maps::loadDem(pdmFile(pdmId)).dem.z;
}

}  // namespace rover::api
