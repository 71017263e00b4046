#include "server/api/map_catalog.hpp"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <csignal>
#include <iostream>
#include <set>
#include <thread>

#include "core/common/error.hpp"
#include "maps/dem_digest.hpp"
#include "maps/dem_io.hpp"
#include "maps/georef.hpp"
#include "maps/gdal_env.hpp"
#include "maps/render.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/http/http_types.hpp"
#include "server/jail/worker_output.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

constexpr std::size_t kMaxFileNameBytes = 200;

// GeoTIFF writes into the data dir: a full disk is the disk's fault, answered 507 like the .f32
// and .png layers (store::StorageFull), never 400 with the file's path.
template <class Write>
void storingGeoTiff(Write&& write) {
  try {
    write();
  } catch (const maps::DiskFull& e) {
    throw store::StorageFull("cannot write " + e.fileName());
  } catch (const Error& e) {
    // Any other failure to write into the data dir is the server's, not the request's: 500 with
    // the detail (which names the server's path) in the log only (routes.cpp's guard).
    if (e.field() == "out") throw std::runtime_error(e.what());
    throw;
  }
}

std::string safeName(const std::string& name, const std::string& fallback) {
  std::string base = fs::path(name).filename().string(), out;
  for (char c : base) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  if (out.empty() || out == "." || out == "..") out = fallback;
  return out;
}

// PNG overviews come in a fixed ladder of sizes: ?max= rounds up to the next rung, and a rung at
// least the map's own size is the full-size rendering, so a layer has at most 6 PNG files.
constexpr int kOverviewLadder[] = {256, 512, 1024, 2048, 4096};

// The longest side of the overview for ?max= (0 = full size).
int overviewSide(int max, int nativeSide) {
  if (max <= 0) return 0;
  for (int rung : kOverviewLadder)
    if (max <= rung) return rung >= nativeSide ? 0 : rung;
  return 0;
}

// A PNG overview named by a size off the ladder (LAYER-N.png, pdm-ID-N.png): written before the
// ladder existed, never asked for again.
bool offLadderOverview(const std::string& file) {
  if (file.size() < 5 || file.compare(file.size() - 4, 4, ".png") != 0) return false;
  const std::string stem = file.substr(0, file.size() - 4);
  const auto dashes = std::count(stem.begin(), stem.end(), '-');
  if (dashes != (stem.rfind("pdm-", 0) == 0 ? 2 : 1)) return false;
  const std::string n = stem.substr(stem.rfind('-') + 1);
  if (n.empty() || n.size() > 6 || !std::all_of(n.begin(), n.end(), [](unsigned char c) { return std::isdigit(c); }))
    return false;
  return std::find(std::begin(kOverviewLadder), std::end(kOverviewLadder), std::stoi(n)) == std::end(kOverviewLadder);
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
          {"dem_sha256", maps::demSha256(d.dem)},
          {"resampling", d.info.resampling},
          {"elevation", {{"min", d.info.minHeight}, {"max", d.info.maxHeight}}},
          {"classes",
           {{"traversable_pct", t.shares.percent(TC::Traversable)},
            {"high_risk_pct", t.shares.percent(TC::HighRisk)},
            {"impassable_pct", t.shares.percent(TC::Impassable)},
            {"nodata_pct", t.shares.percent(TC::NoData)}}}};
}

}  // namespace

MapCatalog::MapCatalog(store::Database& db, store::DataDir& dir, std::int64_t maxCells,
                       std::uint64_t layerCacheBytes)
    : db_(db), dir_(dir), maxCells_(maxCells),
      layers_(fs::path(dir.mapDir("x")).parent_path().string(), layerCacheBytes, offLadderOverview, &dir.budget()) {
  jail_.limits = defaultImportLimits(maxCells);
}

jail::JailLimits MapCatalog::defaultImportLimits(std::int64_t maxCells) {
  jail::JailLimits l;
  const auto cells = static_cast<std::uint64_t>(std::max<std::int64_t>(maxCells, 0));
  // Address space: 1 GiB for the program, GDAL and its block cache, 24 bytes a cell for the grid
  // and the warper's buffers, and 96 MiB a core for the warper's threads (stack + malloc arena).
  l.memoryBytes = (1ull << 30) + 24 * cells + (96ull << 20) * std::max(1u, std::thread::hardware_concurrency());
  l.fileBytes = 4 * cells + (64ull << 20);  // the float32 grid it writes back, and its JSON
  l.cpuSeconds = 600;
  l.deadlineSeconds = 300;
  return l;
}

void MapCatalog::setImportJail(jail::JailConfig config) {
  std::lock_guard lock(mutex_);
  jail_ = std::move(config);
}

jail::JailConfig MapCatalog::importJail() const {
  std::lock_guard lock(mutex_);
  return jail_;
}

maps::LoadedDem MapCatalog::importJailed(const std::string& inDir, jail::ImportRequest req, std::string& rasterName) {
  const jail::JailConfig config = importJail();
  const bool pdm = req.kind == "pdm";
  const std::string invalid = pdm ? "invalid_pdm" : "invalid_dem";
  const std::string what = pdm ? "the PDM raster" : "the file";
  req.allowHdf5 = jail::isolation() == jail::Isolation::Bubblewrap;
  const std::string out = dir_.stagingDir();
  struct RemoveOut {
    std::string path;
    ~RemoveOut() { store::DataDir::removeTree(path); }
  } removeOut{out};
  jail::writeImportRequest(out, req);
  const jail::JailRun run = jail::runJailed(config, inDir, out);
  auto logWorker = [&](const std::string& why) {
    // What the worker said on stderr stays in the server's log; the client gets our words.
    std::ifstream log(fs::path(out) / "worker.log");
    std::string tail((std::istreambuf_iterator<char>(log)), {});
    if (tail.size() > 2000) tail = tail.substr(tail.size() - 2000);
    std::cerr << "import worker: " << why << (tail.empty() ? "" : ": " + tail) << std::endl;
  };
  switch (run.end) {
    case jail::JailRun::End::NotStarted:
      throw std::runtime_error("the import worker did not start: " + run.detail);
    case jail::JailRun::End::DeadlinePassed:
      throw ApiError(400, "import_timeout",
                     "the importer did not finish reading " + what + " within " +
                         std::to_string(static_cast<long long>(config.limits.deadlineSeconds)) + " s",
                     "file");
    case jail::JailRun::End::Signalled:
      if (run.signal == SIGXCPU)
        throw ApiError(413, "too_large", what + " needs more than the " + std::to_string(config.limits.cpuSeconds) +
                                             " s of CPU time an import may use", "file");
      if (run.signal == SIGXFSZ)
        throw ApiError(413, "too_large", what + " makes a grid larger than an import may write", "file");
      logWorker("ended by signal " + std::to_string(run.signal));
      throw ApiError(400, "import_crashed",
                     "the importer crashed (signal " + std::to_string(run.signal) + ") reading " + what, "file");
    case jail::JailRun::End::Exited:
      break;
  }
  if (run.exitStatus == 1) {
    if (auto e = jail::readWorkerError(out)) throw ApiError(e->status, e->code, e->message, e->field);
  }
  if (run.exitStatus != 0) {
    logWorker("exit status " + std::to_string(run.exitStatus));
    throw ApiError(400, "import_failed", "the importer failed reading " + what + " (exit status " +
                                             std::to_string(run.exitStatus) + ")", "file");
  }
  try {
    jail::WorkerResult r = jail::readWorkerResult(out, req.load.maxCells);
    rasterName = r.rasterName;
    return std::move(r.dem);
  } catch (const Error& e) {
    throw ApiError(400, invalid, e.what(), e.field());
  } catch (const std::runtime_error& e) {
    logWorker(e.what());
    throw ApiError(400, invalid, "the importer's output for " + what + " does not read", "file");
  }
}

store::MapRecord MapCatalog::importDem(const std::vector<UploadedFile>& files, const std::string& name,
                                       const maps::DemImport& options) {
  const double cellSize = options.load.cellSize;
  if (files.empty()) throw ApiError(400, "invalid_input", "no DEM file in the request", "file");
  if (!(cellSize >= 0) || !std::isfinite(cellSize) || cellSize > 1e5)
    throw ApiError(400, "invalid_parameter", "cell must be a positive number of metres", "cell");
  rover::json::checkName(name, "name");  // the same rule as every other name (server/json/json_edge.hpp)
  const std::string staging = dir_.stagingDir();
  try {
    std::vector<std::string> sources;
    for (std::size_t i = 0; i < files.size(); ++i) {
      std::string fallback = "upload";
      fallback += std::to_string(i);
      // A file name must fit the file system once staged (NAME_MAX 255) with room for a prefix;
      // cutting it instead would break the names a PDS3 label gives its image.
      if (files[i].filename.size() > kMaxFileNameBytes)
        throw ApiError(400, "invalid_field",
                       "a file name of " + std::to_string(files[i].filename.size()) + " bytes is longer than the " +
                           std::to_string(kMaxFileNameBytes) + " allowed",
                       "filename");
      std::string fname = safeName(files[i].filename, fallback);
      if (std::find(sources.begin(), sources.end(), fname) != sources.end()) {
        std::string unique = std::to_string(i);
        unique += '_';
        fname = unique + fname;
      }
      fs::rename(files[i].path, fs::path(staging) / fname);
      sources.push_back(fname);
    }
    // The client's files are parsed in the import jail (server/jail/): a crash, hang or memory
    // bomb in GDAL ends that worker, never this process.
    jail::ImportRequest req;
    req.kind = "dem";
    req.sources = sources;
    req.load = options.load;
    req.load.maxCells = maxCells_;
    std::string raster;
    maps::LoadedDem d = importJailed(staging, req, raster);
    terrain::Traversability t = terrain::traversability(d.dem);
    storingGeoTiff([&] { maps::writeGeoTiff((fs::path(staging) / "dem.tif").string(), d.dem.z); });
    store::MapRecord rec;
    rec.id = store::DataDir::newId();
    // A default name comes from the file (a zip member's may hold anything): its last path part,
    // hidden controls and bad bytes dropped, at most 200 characters.
    if (name.empty()) {
      rec.name = rover::json::cleanName(fs::path(raster).filename().string());
      if (rec.name.empty()) rec.name = "upload";
    } else {
      rec.name = name;
    }
    rec.createdAt = store::nowIso();
    rec.meta = metaFor(d, t, sources);
    // The body the planners assume: declared with the upload, else read from the CRS.
    const terrain::Body body = options.body ? *options.body : maps::bodyOfCrs(d.dem.z.geo.crsWkt);
    rec.meta["body"] = terrain::bodyName(body);
    rec.meta["body_source"] = options.body ? "declared" : "crs";
    rec.meta["vertical_scale"] = options.load.verticalScale;
    if (options.load.crop) rec.meta["crop"] = *options.load.crop;
    if (options.load.cropPixels) rec.meta["crop_px"] = *options.load.cropPixels;
    // Files first, then the row: a crash in between leaves an orphan folder nobody lists.
    dir_.commitDir(staging, dir_.mapDir(rec.id), store::DiskCharge{store::DiskUse::Map, rec.id, "file"});
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
  importDem({{moved, "default-mars.tif"}}, "Default: synthetic Mars, 150 m (seed 1)");
}

std::shared_ptr<const MapData> MapCatalog::loadFromDisk(const store::MapRecord& r) {
  auto data = std::make_shared<MapData>();
  data->record = r;
  data->dem = maps::loadDem((fs::path(dir_.mapDir(r.id)) / "dem.tif").string()).dem;
  data->traversability = terrain::traversability(data->dem);
  // Maps imported before bodies were stored read theirs from the CRS, as they did then.
  const auto declared = r.meta.contains("body") && r.meta["body"].is_string()
                            ? maps::bodyFromName(r.meta["body"].get<std::string>() == "unknown" ? "auto" : r.meta["body"].get<std::string>())
                            : std::nullopt;
  data->body = declared ? *declared : maps::bodyOfCrs(data->dem.z.geo.crsWkt);
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
  if (!rec) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  auto data = loadFromDisk(*rec);
  std::lock_guard lock(mutex_);
  cache_.push_front(data);
  if (cache_.size() > 4) cache_.pop_back();
  return data;
}

void MapCatalog::remove(const std::string& id) {
  auto pdms = db_.listPdms(id);
  if (!db_.deleteMap(id)) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  {
    std::lock_guard lock(mutex_);
    cache_.remove_if([&](const auto& m) { return m->record.id == id; });
    cellCache_.remove_if([&](const auto& e) { return e.first.rfind(id + "@", 0) == 0; });
  }
  for (const auto& p : pdms) dir_.remove(dir_.pdmDir(p.id));
  layers_.forgetUnder(dir_.mapDir(id));
  dir_.remove(dir_.mapDir(id));
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
  const std::string stored = (fs::path(dir_.mapDir(id)) / "dem.tif").string();
  try {
    dem = std::make_shared<terrain::Dem>(maps::loadDem(stored, o).dem);
  } catch (const Error& e) {
    // Name the map, never the file the server keeps it in.
    std::string msg = e.what();
    if (msg.rfind(stored, 0) == 0) msg = "the map" + msg.substr(stored.size());
    throw ApiError(400, "invalid_parameter", "coverage_cell: " + maps::withoutPaths(msg), "params.coverage_cell");
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
    throw ApiError(404, "not_found", "no layer '" + rover::json::shown(layer) + "' (elevation, hillshade, slope, traversability, pdm)", "layer");
  if (format != "png" && format != "tif" && format != "f32")
    throw ApiError(404, "not_found", "no format '" + rover::json::shown(format) + "' (png, tif, f32)", "format");
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
    if (!rec || rec->mapId != id) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdm) + "' on this map", "pdm");
  }
  const fs::path dir = fs::path(dir_.mapDir(id)) / "layers";
  const GridGeometry& geom = map->dem.geometry();
  const int side = format == "png" ? overviewSide(max, std::max(geom.rows, geom.cols)) : 0;
  std::string file = layer;
  if (layer == "pdm") file += "-" + pdm;
  if (side > 0) {
    file += '-';
    file += std::to_string(side);
  }
  file += '.';
  file += format;
  // Made once per file, outside the catalog's lock (other layers and maps go on meanwhile).
  return layers_.get((dir / file).string(), [&](const std::string& path) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    renderLayerFile(*map, layer, format, side, pdm, path);
  });
}

void MapCatalog::renderLayerFile(const MapData& mapData, const std::string& layer, const std::string& format,
                                 int side, const std::string& pdm, const std::string& path) {
  const MapData* map = &mapData;
  const terrain::Dem& dem = map->dem;
  Raster<float> values;
  if (layer == "elevation") values = dem.z;
  else if (layer == "hillshade") values = terrain::hillshade(dem);
  else if (layer == "slope") values = terrain::slopeHorn(dem);
  else if (layer == "pdm") values = *pdmMass(pdm);
  values.geo = dem.z.geo;
  if (format == "tif") {
    storingGeoTiff([&] {
      if (layer == "traversability") maps::writeClassesGeoTiff(path, map->traversability.classes);
      else maps::writeGeoTiff(path, values);
    });
  } else if (format == "f32") {
    std::string bytes;
    const int n = dem.geometry().cellCount();
    bytes.resize(4ull * n);
    for (int i = 0; i < n; ++i) {
      float v = layer == "traversability" ? static_cast<float>(map->traversability.classes.at(i)) : values.at(i);
      std::memcpy(&bytes[4ull * i], &v, 4);  // x86-64 and aarch64 are little-endian
    }
    store::DataDir::writeFileAtomic(path, bytes);
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
    ro.maxSize = side;
    auto png = maps::encodePng(maps::renderLayer(maps::renderLayerFromName(layer), in, ro));
    store::DataDir::writeFileAtomic(path, std::string(png.begin(), png.end()));
  }
}

std::string MapCatalog::pdmFile(const std::string& pdmId) const {
  return (fs::path(dir_.pdmDir(pdmId)) / "pdm.tif").string();
}

store::PdmRecord MapCatalog::createPdm(const std::string& mapId, const std::string& name,
                                       const std::vector<pdm::Gaussian>& components,
                                       const nlohmann::json& meta) {
  auto map = get(mapId);
  dir_.budget().requireRoom(store::DiskUse::Pdm, mapId, "body");
  // Discretised now to refuse components that put no mass on the map (400), as every later use
  // would; what is stored is the components (the mass is kept in memory for a while).
  Raster<float> mass;
  try {
    mass = pdm::discretise(components, map->dem.geometry(), map->valid);
  } catch (const Error& e) {
    throw ApiError(400, "invalid_parameter", e.what(), e.field());
  }
  mass.geo = map->dem.z.geo;
  const std::string stored = rover::json::toStoredJson(components).dump();
  const store::PdmRecord rec =
      storePdm(mapId, name.empty() ? "PDM " + store::nowIso() : name, meta, [&](const std::string& staging) {
        store::DataDir::writeFileAtomic((fs::path(staging) / "components.json").string(), stored);
      });
  keepMass(rec.id, std::make_shared<const Raster<float>>(std::move(mass)));  // a mission often follows
  return rec;
}

store::PdmRecord MapCatalog::storePdm(const std::string& mapId, const std::string& name, const nlohmann::json& meta,
                                      const std::function<void(const std::string&)>& write) {
  // Files first, then the row, as for maps.
  const std::string staging = dir_.stagingDir();
  try {
    write(staging);
    store::PdmRecord rec;
    rec.id = store::DataDir::newId();
    rec.mapId = mapId;
    rec.name = name;
    rec.createdAt = store::nowIso();
    rec.meta = meta;
    dir_.commitDir(staging, dir_.pdmDir(rec.id), store::DiskCharge{store::DiskUse::Pdm, mapId, "body"});
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
  // The raster is read in a folder of its own, so that it can read nothing else, by the import
  // jail (server/jail/).
  const std::string staging = dir_.stagingDir();
  const std::string stagedName = "pdm-raster" + fs::path(rasterPath).extension().string();
  maps::LoadedDem w;
  try {
    fs::rename(rasterPath, fs::path(staging) / stagedName);
    jail::ImportRequest req;
    req.kind = "pdm";
    req.sources = {stagedName};
    req.load = o;
    std::string shown;
    w = importJailed(staging, req, shown);
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
  store::DataDir::removeTree(staging);
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
  return storePdm(mapId, name.empty() ? "raster PDM" : name, {{"kind", "raster"}}, [&](const std::string& staging) {
    storingGeoTiff([&] { maps::writeGeoTiff((fs::path(staging) / "pdm.tif").string(), mass); });
  });
}

void MapCatalog::keepMass(const std::string& pdmId, std::shared_ptr<const Raster<float>> mass) {
  std::lock_guard lock(mutex_);
  massCache_.remove_if([&](const auto& e) { return e.first == pdmId; });
  massCache_.emplace_front(pdmId, std::move(mass));
  std::int64_t cells = 0;
  for (auto it = massCache_.begin(); it != massCache_.end();) {
    cells += it->second->geometry.cellCount();
    // The newest is kept whatever its size; older ones while they fit.
    if (it != massCache_.begin() && cells > kMassCacheCells) it = massCache_.erase(it);
    else ++it;
  }
}

std::shared_ptr<const Raster<float>> MapCatalog::pdmMass(const std::string& pdmId) {
  {
    std::lock_guard lock(mutex_);
    for (auto it = massCache_.begin(); it != massCache_.end(); ++it)
      if (it->first == pdmId) {
        massCache_.splice(massCache_.begin(), massCache_, it);
        return massCache_.front().second;
      }
  }
  std::shared_ptr<const Raster<float>> mass;
  std::error_code ec;
  if (fs::exists(pdmFile(pdmId), ec)) {
    mass = std::make_shared<const Raster<float>>(maps::loadDem(pdmFile(pdmId)).dem.z);  // raster, or older
  } else {
    const auto rec = db_.getPdm(pdmId);
    if (!rec) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdmId) + "'", "pdm");
    std::ifstream in(fs::path(dir_.pdmDir(pdmId)) / "components.json");
    if (!in) throw std::runtime_error("PDM " + pdmId + ": neither pdm.tif nor components.json is stored");
    const auto components = rover::json::gaussiansFromStoredJson(nlohmann::json::parse(in));
    auto map = get(rec->mapId);
    Raster<float> m = pdm::discretise(components, map->dem.geometry(), map->valid);
    m.geo = map->dem.z.geo;
    mass = std::make_shared<const Raster<float>>(std::move(m));
  }
  keepMass(pdmId, mass);
  return mass;
}

}  // namespace rover::api
