// MapCatalog::tileFile: tiles of a map's layers (issue 24) as files in the layer cache.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "core/common/error.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/map_tiles.hpp"
#include "server/api/map_files.hpp"
#include "server/api/map_catalog.hpp"
#include "server/errors/domain_error.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

// The tile grid from the stored size, so a hostile address is answered without loading the map.
maps::TileGrid storedGrid(const store::MapRecord& r, MapCatalog& catalog) {
  const auto& m = r.meta;
  if (m.contains("rows") && m["rows"].is_number_integer() && m.contains("cols") && m["cols"].is_number_integer())
    return maps::tileGridOf(m["rows"].get<int>(), m["cols"].get<int>());
  const GridGeometry& g = catalog.get(r.id)->dem.geometry();  // a map stored without its size
  return maps::tileGridOf(g.rows, g.cols);
}

// A tile's bytes: f32 values or an encoded PNG, from the stored pyramid (maps::TileBlocks) or the
// map in memory (maps::TileSource).
template <class Source>
std::string tileBytes(const Source& blocks, maps::RenderLayer layer, const std::string& format,
                      const maps::TileWindow& window) {
  std::string bytes;
  if (format == "f32") {
    const auto values = maps::tileValues(layer, blocks, window);
    bytes.resize(values.size() * 4);
    std::memcpy(bytes.data(), values.data(), bytes.size());  // x86-64 and aarch64 are little-endian
  } else {
    // The fewest bytes a pixel that give the same RGBA (a palette, grey or RGB where they can):
    // less to deflate, store and send.
    const auto png = maps::encodePng(maps::renderTile(layer, blocks, window), maps::PngColours::Smallest);
    bytes.assign(png.begin(), png.end());
  }
  return bytes;
}

// A tile's layer and format: 404 for any other (checked before anything is read).
void checkTileKind(const std::string& layer, const std::string& format) {
  static const char* const kLayers[] = {"elevation", "hillshade", "slope", "traversability", "pdm"};
  if (std::none_of(std::begin(kLayers), std::end(kLayers), [&](const char* l) { return layer == l; }))
    throw ApiError(404, "not_found", "no layer '" + rover::json::shown(layer) + "' (elevation, hillshade, slope, traversability, pdm)", "layer");
  if (format != "png" && !(format == "f32" && (layer == "elevation" || layer == "slope")))
    throw ApiError(404, "not_found", "tiles are .png for every layer, .f32 for elevation and slope", "format");
}

// The tile's cells, or 404 for an address outside the map's grid.
maps::TileWindow tileWindowOr404(const maps::TileGrid& grid, long long z, long long x, long long y) {
  const auto window = maps::tileWindow(grid, z, x, y);
  if (!window)
    throw ApiError(404, "not_found",
                   "no tile " + std::to_string(z) + "/" + std::to_string(x) + "/" + std::to_string(y) +
                       " (zoom 0.." + std::to_string(grid.maxZoom()) + ")",
                   "tile");
  return *window;
}

// The tile's file in the layer cache: layers/t1-LAYER[-PDM[-vN]]-Z-X-Y.FORMAT.
fs::path tilePath(const fs::path& layersDir, const std::string& layer, const std::string& pdmAndVersion, long long z,
                  long long x, long long y, const std::string& format) {
  // Appended piece by piece: GCC 12's -Wrestrict misreads a chain of operator+ here.
  std::string file = MapCatalog::kTileVersion;
  file += '-';
  file += layer;
  for (const std::string& part : {pdmAndVersion, std::to_string(z), std::to_string(x), std::to_string(y)}) {
    if (part.empty()) continue;
    file += '-';
    file += part;
  }
  file += '.';
  file += format;
  return layersDir / file;
}

}  // namespace

std::shared_ptr<const maps::DemHeader> MapCatalog::storedHeader(const std::string& id) {
  std::uint64_t invalidations = 0;
  {
    std::lock_guard lock(mutex_);
    for (auto it = headerCache_.begin(); it != headerCache_.end(); ++it)
      if (it->first == id) {
        headerCache_.splice(headerCache_.begin(), headerCache_, it);
        return it->second;
      }
    invalidations = invalidations_;
  }
  std::shared_ptr<const maps::DemHeader> h;
  try {
    h = std::make_shared<const maps::DemHeader>(
        readElevation(dir_.mapDir(id), [](const std::string& path) { return maps::readDemHeader(path); }));
  } catch (const Error& e) {
    throw std::runtime_error(e.what());  // the stored file is the server's: 500, its path in the log only
  }
  if (raceHooks.afterHeaderRead) raceHooks.afterHeaderRead(id);
  std::lock_guard lock(mutex_);
  // A header read while the map's storage changed (the raw VRT's, read as its COG replaced it) or
  // the map went is returned this once, not kept: forgetStoredElevation ran before it could be.
  if (invalidations != invalidations_) return h;
  headerCache_.emplace_front(id, h);
  if (headerCache_.size() > 16) headerCache_.pop_back();
  return h;
}

std::shared_ptr<const MapCatalog::StoredTiles> MapCatalog::cachedStoredTiles(const std::string& id) {
  std::lock_guard lock(mutex_);
  for (auto it = tilesCache_.begin(); it != tilesCache_.end(); ++it)
    if ((*it)->id == id) {
      tilesCache_.splice(tilesCache_.begin(), tilesCache_, it);
      return *it;
    }
  return nullptr;
}

std::shared_ptr<const MapCatalog::StoredTiles> MapCatalog::storedTiles(const std::string& id) {
  if (auto cached = cachedStoredTiles(id)) return cached;
  std::uint64_t invalidations = 0;
  {
    std::lock_guard lock(mutex_);
    invalidations = invalidations_;
  }
  auto rec = db_.getMap(id);
  if (!rec) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  auto t = std::make_shared<StoredTiles>();
  t->id = id;
  t->grid = storedGrid(*rec, *this);
  t->pyramid = storedAsPyramid(*rec, dir_.mapDir(id));
  if (t->pyramid) t->ramp = {rec->meta["colour_range"][0].get<double>(), rec->meta["colour_range"][1].get<double>()};
  std::lock_guard lock(mutex_);
  if (invalidations != invalidations_) return t;  // the map may be gone: this once, uncached
  tilesCache_.emplace_front(t);
  if (tilesCache_.size() > 16) tilesCache_.pop_back();
  return t;
}

std::optional<std::string> MapCatalog::madeTile(const std::string& id, const std::string& layer,
                                                const std::string& format, long long z, long long x, long long y) {
  checkTileKind(layer, format);
  if (layer == "pdm") return std::nullopt;  // its version is the database's
  const auto stored = cachedStoredTiles(id);
  if (!stored) return std::nullopt;
  tileWindowOr404(stored->grid, z, x, y);
  const std::string path = tilePath(fs::path(dir_.mapDir(id)) / "layers", layer, "", z, x, y, format).string();
  if (!layers_.tryUse(path)) return std::nullopt;
  return path;
}

MapCatalog::Tile MapCatalog::tileFile(const std::string& id, const std::string& layer, const std::string& format,
                                 long long z, long long x, long long y, const std::string& pdmId) {
  checkTileKind(layer, format);
  const auto stored = storedTiles(id);
  // A pdm tile names its PDM's version now (an edited PDM's tiles are new files, issue 26): 404
  // when the PDM is gone or not on this map.
  auto pdmVersionNow = [&] {
    auto p = db_.getPdm(pdmId);
    if (!p || p->mapId != id) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdmId) + "' on this map", "pdm");
    return pdmVersionTag(p->version);
  };
  std::string pdmVersion;
  if (layer == "pdm") {
    if (pdmId.empty()) throw ApiError(400, "invalid_parameter", "a pdm tile names its PDM: ?pdm=ID", "pdm");
    pdmVersion = pdmVersionNow();
  }
  const maps::TileWindow window = tileWindowOr404(stored->grid, z, x, y);
  const fs::path dir = fs::path(dir_.mapDir(id)) / "layers";
  Tile tile;
  // The tile's file (of PDM version `version` for a pdm tile), made once per file on the work
  // pool, outside the catalog's lock.
  auto tileOf = [&](const std::string& version) {
    const fs::path file = tilePath(dir, layer, layer == "pdm" ? pdmId + version : "", z, x, y, format);
    tile.made.clear();
    return layers_.get(file.string(), [&](const std::string& path) {
      std::error_code ec;
      fs::create_directories(dir, ec);
      const auto l = maps::renderLayerFromName(layer);
      const fs::path mapDir = dir_.mapDir(id);
      if (layer == "pdm") {
        // The PDM's mass pyramid (made once per PDM version): the tile's window at its zoom and the
        // ramp stored with it, never the whole mass or the map.
        const std::string pyramid = pdmPyramidFile(id, pdmId, version);
        if (raceHooks.beforePdmPyramidRead) raceHooks.beforePdmPyramidRead(pdmId);
        const maps::MassPyramidBlocks blocks(pyramid, storedHeader(id)->geometry);
        tile.made = tileBytes(blocks, l, format, window);
        store::DataDir::writeFileAtomic(path, tile.made, false);  // a cache file: no fsync
        return;
      }
      if (stored->pyramid) {
        // The level of the tile's zoom, about (256 + 2)² cells: the map is never loaded.
        const auto header = storedHeader(id);
        tile.made = readElevation(mapDir.string(), [&](const std::string& dem) {
          return tileBytes(maps::PyramidBlocks(dem, (mapDir / kClassFile).string(), header, stored->ramp), l, format,
                           window);
        });
        store::DataDir::writeFileAtomic(path, tile.made, false);  // a cache file: no fsync
        return;
      }
      auto map = get(id);  // a map stored before the pyramid: the whole map in memory
      maps::TileSource src;
      src.dem = &map->dem;
      src.classes = &map->traversability.classes;
      src.range = map->elevationRange;
      tile.made = tileBytes(src, l, format, window);
      store::DataDir::writeFileAtomic(path, tile.made, false);
    });
  };
  if (layer != "pdm") {
    tile.path = tileOf("");
    return tile;
  }
  // A pdm tile races its PDM's edits and deletion: the version resolved above may be edited or
  // deleted before its mass pyramid is read (forgetPdm removes that version's files: the
  // pyramid's open fails, or pdmPyramidFile finds another version, 409), or evicted from the
  // layer cache meanwhile. Then the PDM is resolved again and its current version drawn, once;
  // a PDM gone meanwhile is 404. Another edit during that second drawing is a 409 (ask again),
  // never a 500; a failure of the same version's file that is the request's (413, 507) stands.
  for (int attempt = 0;; ++attempt) {
    try {
      tile.path = tileOf(pdmVersion);
      tile.pdmVersion = pdmVersion;
      return tile;
    } catch (const std::exception& e) {
      const std::string now = pdmVersionNow();  // 404 when the PDM went meanwhile
      const bool requests = dynamic_cast<const ApiError*>(&e) || dynamic_cast<const DomainError*>(&e);
      if (now == pdmVersion && requests) throw;
      if (attempt > 0) {
        if (now == pdmVersion) throw;  // its own file does not read: the server's fault
        throw ApiError(409, "conflict", "the PDM was edited while this tile was drawn: ask again", "pdm");
      }
      pdmVersion = now;
    }
  }
}

}  // namespace rover::api
