#include "server/api/map_catalog.hpp"

// The catalog's maps in memory (a few recent ones, and resampled DEMs per cell size), their
// removal and the layer files. Imports: map_import.cpp; PDMs: map_pdms.cpp.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/georef.hpp"
#include "maps/layer_overview.hpp"
#include "maps/gdal_env.hpp"
#include "server/api/map_files.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/store/disk_budget.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

// "25 M" for whole millions (the default), else the number: the limit as a message states it.
std::string cellsInWords(std::int64_t cells) {
  return cells % 1'000'000 == 0 ? std::to_string(cells / 1'000'000) + " M" : std::to_string(cells);
}

}  // namespace

MapCatalog::MapCatalog(store::Database& db, store::DataDir& dir, std::int64_t maxCells,
                       std::uint64_t layerCacheBytes)
    : db_(db), dir_(dir), maxCells_(maxCells),
      layers_(fs::path(dir.mapDir("x")).parent_path().string(), layerCacheBytes, offLadderOverview, &dir.budget()) {
  jail_.limits = defaultImportLimits(maxCells);
  compressor_ = std::make_unique<ElevationCompressor>(
      [this](const std::string& id, const std::function<bool()>& cancelled) { compressElevation(id, cancelled); });
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

terrain::Body mapBody(const store::MapRecord& r, const std::string& crsWkt) {
  // Maps imported before bodies were stored read theirs from the CRS, as they did then.
  const auto declared = r.meta.contains("body") && r.meta["body"].is_string()
                            ? maps::bodyFromName(r.meta["body"].get<std::string>() == "unknown" ? "auto" : r.meta["body"].get<std::string>())
                            : std::nullopt;
  return declared ? *declared : maps::bodyOfCrs(crsWkt);
}

std::shared_ptr<const MapData> MapCatalog::loadFromDisk(const store::MapRecord& r) {
  auto data = std::make_shared<MapData>();
  data->record = r;
  data->dem = readElevation(dir_.mapDir(r.id), [](const std::string& path) {
    try {
      return maps::loadDem(path).dem;
    } catch (const Error& e) {
      throw std::runtime_error(e.what());  // the stored file is the server's: 500, its path in the log only
    }
  });
  data->traversability = terrain::traversability(data->dem);
  data->elevationRange = maps::colourRange(maps::RenderLayer::Elevation, data->dem.z);
  data->body = mapBody(r, data->dem.z.geo.crsWkt);
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
    headerCache_.remove_if([&](const auto& e) { return e.first == id; });
    tilesCache_.remove_if([&](const auto& t) { return t->id == id; });
    ++invalidations_;
  }
  // Its COG job, if any, ends before the folder goes (it never makes the folder again).
  compressor_->cancel(id);
  for (const auto& p : pdms) dir_.remove(dir_.pdmDir(p.id));
  layers_.forgetUnder(dir_.mapDir(id));
  maps::forgetStoredRasters(dir_.mapDir(id));  // open tile readers (maps/dem_pyramid.hpp)
  dir_.remove(dir_.mapDir(id));
}

std::shared_ptr<const terrain::Dem> MapCatalog::demAtCell(const std::string& id, double cellSize) {
  auto map = get(id);
  if (cellSize <= 0 || std::fabs(cellSize - map->dem.geometry().cellWidth) < 1e-9)
    return std::shared_ptr<const terrain::Dem>(map, &map->dem);
  const std::string key = id + "@" + std::to_string(cellSize);
  std::uint64_t invalidations = 0;
  {
    std::lock_guard lock(mutex_);
    for (auto& e : cellCache_)
      if (e.first == key) return e.second;
    invalidations = invalidations_;
  }
  maps::LoadOptions o;
  o.cellSize = cellSize;
  o.maxCells = maxCells_;
  std::shared_ptr<const terrain::Dem> dem;
  dem = readElevation(dir_.mapDir(id), [&](const std::string& stored) {
    try {
      return std::make_shared<terrain::Dem>(maps::loadDem(stored, o).dem);
    } catch (const Error& e) {
      // Name the map, never the file the server keeps it in.
      std::string msg = e.what();
      if (msg.rfind(stored, 0) == 0) msg = "the map" + msg.substr(stored.size());
      throw ApiError(400, "invalid_parameter", "coverage_cell: " + maps::withoutPaths(msg), "params.coverage_cell");
    }
  });
  std::lock_guard lock(mutex_);
  if (invalidations != invalidations_) return dem;  // read from a file since replaced: this once, uncached
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
  auto rec = db_.getMap(id);
  if (!rec) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  std::string pdm = pdmId;
  if (layer == "pdm" && pdm.empty()) {
    auto list = db_.listPdms(id);
    if (list.empty()) throw ApiError(404, "not_found", "the map has no PDM yet", "pdm");
    pdm = list.back().id;
  }
  std::string pdmVersion;  // an edited PDM's layers are new files (issue 26)
  if (layer == "pdm") {
    auto p = db_.getPdm(pdm);
    if (!p || p->mapId != id) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdm) + "' on this map", "pdm");
    pdmVersion = pdmVersionTag(p->version);
  }
  const fs::path mapDir = dir_.mapDir(id);
  // A map stored as its pyramid answers from its files; one stored before is loaded whole.
  const bool pyramid = storedAsPyramid(*rec, mapDir.string());
  const GridGeometry geom = pyramid ? storedHeader(id)->geometry : get(id)->dem.geometry();
  const int side = format == "png" ? overviewSide(max, std::max(geom.rows, geom.cols)) : 0;
  const std::int64_t cells = static_cast<std::int64_t>(geom.rows) * geom.cols;
  const bool big = pyramid && side == 0 && cells > wholeLayerCells();
  if (big) {
    // Full size on a big map: the elevation and class GeoTIFFs are the stored files themselves
    // (the COG and the class pyramid); elevation, slope and hillshade are computed band by band
    // from the stored DEM (below); anything else would be computed on the whole map in memory,
    // which a big map refuses rather than load gigabytes for one file.
    if (format == "tif" && layer == "elevation") {
      // The stored COG itself. A map whose COG is still being written (storage "raw": seconds)
      // is asked again later: a wait here would hold one of the work pool's few threads.
      if (!fs::exists(mapDir / kDemFile) || fs::exists(mapDir / kRawDemDir / kRawDemVrt))
        throw ApiError(503, "not_ready", "the map's elevation is still being compressed: ask again shortly", "layer")
            .withHeader("Retry-After", "10");
      return (mapDir / kDemFile).string();
    }
    if (format == "tif" && layer == "traversability") return (mapDir / kClassFile).string();
    const std::string size = std::to_string(geom.rows) + " x " + std::to_string(geom.cols) + " cells";
    const bool banded = layer == "elevation" || layer == "slope" || layer == "hillshade";
    if (banded && format == "f32" && 4ull * static_cast<std::uint64_t>(cells) > maxStreamedF32Bytes())
      throw ApiError(413, "too_large",
                     "a full-size " + layer + ".f32 of this map (" + size + ") would be " +
                         store::megabytes(4ull * static_cast<std::uint64_t>(cells)) +
                         " uncompressed, over the " + store::megabytes(maxStreamedF32Bytes()) +
                         " a raw export may take of the layer cache: ask for " + layer +
                         ".tif (the same values, compressed), or its .f32 tiles",
                     "layer");
    if (!banded || format == "png")
      throw ApiError(413, "too_large",
                     "a full-size " + layer + "." + format + " of this map (" + size +
                         ") would load the whole map; on maps over " + cellsInWords(wholeLayerCells()) +
                         " cells the full-size files are elevation, slope and hillshade as .tif and .f32, and "
                         "traversability.tif: ask for one of them, a ?max= overview, or the tiles",
                     "layer");
  }
  const fs::path dir = mapDir / "layers";
  std::string file = layer;
  if (layer == "pdm") file += "-" + pdm + pdmVersion;
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
    if (pyramid && side > 0) {
      // From the pyramid's level that fits the overview: the map is never loaded.
      const auto l = maps::renderLayerFromName(layer);
      maps::Image pic;
      if (layer == "pdm") {
        pic = maps::renderOverview(l, maps::MassPyramidBlocks(pdmPyramidFile(id, pdm, pdmVersion), geom), geom.rows,
                                   geom.cols, side);
      } else {
        const auto& ramp = rec->meta["colour_range"];
        const auto header = storedHeader(id);
        pic = readElevation(mapDir.string(), [&](const std::string& dem) {
          return maps::renderOverview(l,
                                      maps::PyramidBlocks(dem, (mapDir / kClassFile).string(), header,
                                                          {ramp[0].get<double>(), ramp[1].get<double>()}),
                                      geom.rows, geom.cols, side);
        });
      }
      const auto png = maps::encodePng(pic);
      store::DataDir::writeFileAtomic(path, std::string(png.begin(), png.end()));
      return;
    }
    if (big) {
      // Band by band from the stored DEM (the raw VRT or the COG: readElevation reads again from
      // the COG if the swap removed the VRT mid-way; the file is written atomically, so a second
      // pass only replaces the temporary file).
      const auto header = storedHeader(id);
      readElevation(mapDir.string(),
                    [&](const std::string& dem) { streamLayerFile(dem, *header, layer, format, path); });
      return;
    }
    auto map = get(id);
    const auto mass = layer == "pdm" ? pdmMass(pdm) : nullptr;
    renderLayerFile(*map, layer, format, side, mass.get(), path);
  });
}

}  // namespace rover::api
