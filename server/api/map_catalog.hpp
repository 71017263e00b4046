#pragma once
// Maps and PDMs of the server: imports uploaded DEMs (any GDAL format, also PDS3 pairs and zips)
// into the data dir, keeps recently used maps loaded, and produces layers (PNG/GeoTIFF/raw float32)
// on demand, cached as files next to the map (LayerCache: a size cap, made once per file). Every
// user-supplied raster is read through maps::openUpload inside its own staging folder.
// Its parts: map_catalog.cpp (the maps in memory, layer files: map_files.hpp), map_import.cpp
// (imports), map_pdms.cpp (PDMs).
#include <atomic>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/pdm/pdm.hpp"
#include "core/planning/mission_area.hpp"
#include "core/terrain/layers.hpp"
#include "maps/dem_import_options.hpp"
#include "maps/dem_io.hpp"
#include "maps/render.hpp"
#include "maps/tile_grid.hpp"
#include "server/api/elevation_compressor.hpp"
#include "server/api/layer_cache.hpp"
#include "server/jail/import_jail.hpp"
#include "server/jail/worker_output.hpp"
#include "server/store/data_dir.hpp"
#include "server/store/database.hpp"

namespace rover::api {

struct MapData {
  store::MapRecord record;
  terrain::Dem dem;
  terrain::Traversability traversability;
  std::vector<std::uint8_t> valid;  // cells with data
  terrain::Body body = terrain::Body::Unknown;  // declared at upload, else from the CRS
  maps::ColourRange elevationRange;  // the elevation ramp of every tile (the full-size picture's)
};

// What a mission needs to know of a map before it plans: its grid, georeferencing and body, from
// the stored DEM's header (no cell read), so a mission area on a 49 M-cell map never loads it.
struct MapHeader {
  GridGeometry geometry;
  GeoReference geo;
  terrain::Body body = terrain::Body::Unknown;
};

struct UploadedFile {
  std::string path;      // where the bytes are now (moved away on import)
  std::string filename;  // the client's name for it ("" when unknown)
};

class ImportStages;  // server/api/import_stages.hpp

class MapCatalog {
 public:
  // Layer files (PNG/GeoTIFF/f32 renderings) are a cache of at most layerCacheBytes per data dir.
  static constexpr std::uint64_t kDefaultLayerCacheBytes = 1ull << 30;
  // The cell budget of a map (issue 24: a full HiRISE DTM is 50–300 M cells). What holds a map of
  // this size whole is the import (a float grid and its classes, README) and the paths that load
  // it whole (get()): whole-map layer files, PDMs, missions without an area, which big maps refuse.
  static constexpr std::int64_t kDefaultMaxCells = 300'000'000;
  MapCatalog(store::Database& db, store::DataDir& dir, std::int64_t maxCells = kDefaultMaxCells,
             std::uint64_t layerCacheBytes = kDefaultLayerCacheBytes);

  // Validates and stores a DEM; throws http::ApiError 400 (field "file"/"cell"/"name") on bad input.
  // `options`: cell size, crop window (CRS or pixels), vertical scale, declared body.
  store::MapRecord importDem(const std::vector<UploadedFile>& files, const std::string& name,
                             const maps::DemImport& options = {});
  // Start-up: queues the COG of every map still stored raw (the server stopped before its
  // compressor finished); it stays readable raw meanwhile. Returns how many were queued.
  int resumeCompressions();
  // Maps of at least this many cells are committed with their elevation raw and compressed in the
  // background (issue 24); smaller ones get their COG before the upload answers (under a second at
  // 4 M cells), so most maps are never seen raw. Tests lower it to see small maps raw.
  static constexpr std::int64_t kDefaultBackgroundCells = 4'000'000;
  void setBackgroundCells(std::int64_t cells) { backgroundCells_ = cells; }
  // The compressor of raw maps (tests wait on it, and hold a job with its hook).
  ElevationCompressor& compressor() { return *compressor_; }
  // Called on the compressor's thread after a map's storage changed (raw -> cog), so the API's
  // cached map bodies are dropped and clients told.
  std::function<void(const std::string& mapId)> onStorageChanged;
  // Tests: called where a read can race a write, so that a test runs the write exactly there
  // (set before the first request): `afterHeaderRead(mapId)` when storedHeader has read a header
  // and not yet kept it; `beforePdmPyramidRead(pdmId)` when a pdm tile has its version's mass
  // pyramid file and has not yet opened it.
  struct RaceHooks {
    std::function<void(const std::string& mapId)> afterHeaderRead;
    std::function<void(const std::string& pdmId)> beforePdmPyramidRead;
  } raceHooks;
  // Start-up: removes map and PDM folders that have no database row (a crash between committing
  // the files and inserting the row leaves one behind). Returns how many were removed.
  int sweepOrphans();
  // The generated default map (synthetic Mars, 600×600 × 0.25 m, seed 1), created if no map exists.
  void ensureDefaultMap();
  // Throws ApiError 404 (field "id") for an unknown map.
  std::shared_ptr<const MapData> get(const std::string& id);
  void remove(const std::string& id);

  // The stored DEM's header (grid, per-row widths, the file's driver), read once per map for its
  // tiles (map_tile_files.cpp); a few maps are kept, a map's dropped when its storage changes
  // (raw -> cog: forgetStoredElevation) or it is removed.
  std::shared_ptr<const maps::DemHeader> storedHeader(const std::string& id);
  // The map's header (map_window.cpp): from the loaded map when it is in memory, else from the
  // stored DEM's header. Throws ApiError 404 (field "id") for an unknown map.
  MapHeader header(const std::string& id);
  // The cells of a planning window of the map (core/planning/mission_area.hpp) read from the
  // stored GeoTIFF's window alone (maps::loadDemWindow): the whole map is never loaded.
  std::shared_ptr<const terrain::Dem> demWindow(const std::string& id, const PlanningWindow& window);
  // The PDM's mass on a planning window, only where `inArea` is 1 (and the window has data),
  // normalised to sum 1 there: the probability to search, given that it lies in the mission
  // area. A Gaussian PDM is discretised on the window (its components moved into the window's
  // frame), a raster PDM read from its stored GeoTIFF's window; neither touches the whole map.
  std::shared_ptr<const Raster<float>> pdmMassIn(const std::string& pdmId, const PlanningWindow& window,
                                                 const terrain::Dem& windowDem,
                                                 const std::vector<std::uint8_t>& inArea);

  // The map resampled to a coverage cell size (cached per cell size).
  std::shared_ptr<const terrain::Dem> demAtCell(const std::string& id, double cellSize);

  // A layer file (elevation|hillshade|slope|traversability|pdm) as png/tif/f32, created on first
  // use; `max` > 0 for a downsampled PNG overview, its size rounded up to the ladder 256, 512,
  // 1024, 2048, 4096 (or the full size when that is smaller). Returns the file path.
  // A map stored as its pyramid (issue 24) draws its overviews from the pyramid's level that fits
  // (maps/layer_overview.hpp) and a pdm overview from the PDM's mass pyramid, never loading the
  // map. Its full-size files (png without max, tif, f32) are computed on the whole map in memory
  // up to wholeLayerCells(); beyond, elevation.tif and traversability.tif are its stored COG and
  // class pyramid, slope.tif and hillshade.tif, and elevation, slope and hillshade .f32 up to
  // maxStreamedF32Bytes(), are computed band by band from the stored DEM (streamLayerFile:
  // the whole-map values, memory a band of rows), and the rest (full-size png, traversability
  // and pdm f32, pdm tif, a larger f32) are refused (ApiError 413 too_large, naming the size and
  // what is made). A map stored before the pyramid is loaded whole (get()) for every layer file.
  std::string layerFile(const std::string& id, const std::string& layer, const std::string& format,
                        int max, const std::string& pdmId);
  // The largest map whose full-size layer files are computed in memory: the map loaded with its
  // traversability (get(): a 49 M-cell map's elevation overview peaked at 728 MiB that way, about
  // 15 bytes a cell) plus the layer's own grid, about 0.5 GB at this size. Tests lower it to see
  // small maps take the streamed path.
  static constexpr std::int64_t kDefaultWholeLayerCells = 25'000'000;
  void setWholeLayerCells(std::int64_t cells) { wholeLayerCells_ = cells; }
  std::int64_t wholeLayerCells() const { return wholeLayerCells_; }
  // The largest full-size .f32 made band by band: a quarter of the layer cache (256 MiB, 67 M
  // cells, at the default 1 GiB). An f32 is 4 bytes a cell uncompressed (1.2 GB for a 300 M-cell
  // map, more than the whole default cache); a quarter leaves the rest of the cache to the tiles
  // and overviews being viewed. Beyond it the .tif holds the same values, compressed.
  std::uint64_t maxStreamedF32Bytes() const { return layers_.capBytes() / 4; }

  // A tile of a layer (maps/tile_grid.hpp, maps/map_tiles.hpp) as png (any layer) or f32
  // (elevation, slope: kTileSize² little-endian float32), created on first use in the layer cache
  // (file layers/t1-LAYER[-PDM]-Z-X-Y.FORMAT). A map stored as its pyramid (maps/dem_pyramid.hpp)
  // draws elevation, hillshade, slope and traversability tiles from the level of the tile's zoom,
  // never loading the map; pdm tiles, and every tile of a map stored before the pyramid, come from
  // the map in memory (get()). The address is checked against the map's stored
  // size before anything is loaded: z/x/y outside the grid, an unknown layer or format → ApiError
  // 404; a pdm tile names its PDM (`pdmId` required: a tile never changes, "the newest" would).
  // The tile's file, and its bytes when this call made it (empty when the file was there): a fresh
  // tile is answered from memory, not read back from the disk it was just written to.
  // A pdm tile is of its PDM's version when it was drawn (`pdmVersion`, pdmVersionTag): an edit or
  // delete that races the request is answered with the current version's tile, or 404 for a
  // deleted PDM (ApiError 409 only if it is edited again while that is drawn), never a tile of
  // one version named by another's ETag.
  struct Tile {
    std::string path;
    std::string made;
    std::string pdmVersion;
  };
  // The renderer's version, first in a tile's file name and ETag: a new renderer names new files
  // and tags, so no client keeps an old one's tile (they are cached as immutable).
  static constexpr const char* kTileVersion = "t1";
  Tile tileFile(const std::string& id, const std::string& layer, const std::string& format, long long z, long long x,
                long long y, const std::string& pdmId);
  // The tile's file when it is already made, from memory alone (the catalog's and the layer
  // cache's maps; no database, no disk), for an answer on an io thread (RouteOptions::quick):
  // nullopt when it is not made, the map's tile grid is not in memory yet, or the layer is pdm (its
  // version is the database's). A wrong layer, format or address of a map in memory throws
  // ApiError 404 as tileFile does.
  std::optional<std::string> madeTile(const std::string& id, const std::string& layer, const std::string& format,
                                      long long z, long long x, long long y);

  // PDMs: from JSON ({"components":[...]} or {"random": G, "seed": S}) or a raster upload.
  // Stored compactly (issue 22: a random 3-component PDM on a 49 M-cell map was a 164 MB GeoTIFF):
  // a Gaussian PDM as its components (components.json, under 1 KB), discretised again on the map's
  // grid when a mission or a layer needs it (pdm::discretise is deterministic: the same mass every
  // time); a raster PDM as a DEFLATE GeoTIFF with the floating-point predictor (pdm.tif). A PDM
  // stored as pdm.tif by an older version is read as it is. Each PDM is charged to its map's disk
  // budget (413/507 beyond it, field "body").
  store::PdmRecord createPdm(const std::string& mapId, const std::string& name,
                             const std::vector<pdm::Gaussian>& components, const nlohmann::json& meta,
                             const std::string& by = "");
  store::PdmRecord createPdmFromRaster(const std::string& mapId, const std::string& name,
                                       const std::string& rasterPath, const std::string& by = "");
  // Each is discretised on the map's grid and cells with data without loading the map (header(),
  // validCells), and its mass pyramid (pdmPyramidFile) made before the call returns.
  // A PDM's new name and (Gaussian PDMs only) components as version expected+1 (issue 26):
  // discretised first (400 when they put no mass on the map), then its components.json and row
  // written in the row's transaction once the version matches. Returns the row's outcome (Stale:
  // nothing written) and, when Done, the new record in `out`.
  store::Cas changePdm(const store::PdmRecord& current, const std::string& name,
                       const std::optional<std::vector<pdm::Gaussian>>& components, long long expected,
                       const std::string& by, store::PdmRecord& out);
  // The file-name part that names a PDM's version in layer and tile files ("" for version 1).
  // Drops what is kept for PDM `pdmId` of map `mapId` but version `keepVersionTag` (all of it
  // when nullopt: a deleted PDM): its cached masses, and its layer files (tiles, overviews, mass
  // pyramids: layers/[t1-]pdm-ID[-vN]...), which no request names once the version has changed.
  void forgetPdm(const std::string& mapId, const std::string& pdmId, const std::optional<std::string>& keepVersionTag);
  static std::string pdmVersionTag(long long version);
  // The PDM's probability mass on its map's grid: a raster PDM's pdm.tif as it is, a Gaussian
  // one discretised on the map's grid and cells with data (from the map in memory when it is
  // loaded, else its stored header and validCells): the map is not loaded for it. Memory: 4 bytes
  // a cell for the mass, and for a Gaussian PDM 9 more while it is discretised (pdm::discretise's
  // double sums and the cells with data). The last few are kept in memory (at most
  // kMassCacheCells cells together: one PDM of a 50 M-cell map), so launching missions with a PDM
  // just made or viewed costs no second discretisation. Kept by PDM and version, so an edit's
  // commit and its new mass never mix (a tile of the new version drawn from the old mass).
  std::shared_ptr<const Raster<float>> pdmMass(const std::string& pdmId);
  // The same for the version `rec` names: a Gaussian PDM's components from the record when it
  // holds them (an edit commits them with its version), else from its components.json.
  std::shared_ptr<const Raster<float>> pdmMassOf(const store::PdmRecord& rec);
  static constexpr std::int64_t kMassCacheCells = 64'000'000;
  std::string pdmFile(const std::string& pdmId) const;
  // The PDM's mass pyramid (maps::writeMassCog: its mass on the map's grid with overviews and its
  // ramp) for version `versionTag` (pdmVersionTag), a file of the layer cache
  // (layers/pdm-ID[-vN]-mass.tif) made from that version's mass on first use and again after an
  // eviction; a version edited since is a 409 (ask again), never a file of another version's mass.
  // An edited PDM is a new version, so a new file: the tiles and ETags of each version stay its own.
  // Memory while it is made: pdmMass's (below), then GDAL's COG writer over that grid in place.
  std::string pdmPyramidFile(const std::string& mapId, const std::string& pdmId, const std::string& versionTag);
  // Makes the pyramid of a PDM just created or changed, while its mass is in memory, so its first
  // tile reads a window (a failure is left to that tile: the PDM itself is stored).
  void keepPyramid(const std::string& mapId, const std::string& pdmId, const std::string& versionTag);

  // How client files are parsed: DEM and PDM-raster uploads run GDAL in an import worker
  // (server/jail/import_jail.hpp) with these limits, never in this process. Tests swap the worker.
  void setImportJail(jail::JailConfig config);
  jail::JailConfig importJail() const;
  // The limits for a cell budget: memory, file size, CPU time and wall clock (stated in README).
  static jail::JailLimits defaultImportLimits(std::int64_t maxCells);

 private:
  // Runs the import worker on the client's files in `inDir`; answers ApiError 400/413 for the
  // file's faults (its own message, a crash with the signal, a deadline), 500 when it cannot start.
  // With `rows`, the heights are not kept: the result's raster has its geometry and no values,
  // and `rows(header, firstRow, count, values)` sees them in checked chunks, in order
  // (jail::readWorkerGrid; `header`: the grid's geometry, georeferencing and row widths).
  using GridRows = std::function<void(const terrain::Dem&, int, int, const float*)>;
  maps::LoadedDem importJailed(const std::string& inDir, jail::ImportRequest req, std::string& rasterName,
                               ImportStages* stages = nullptr, const GridRows* rows = nullptr);
  std::shared_ptr<const MapData> loadFromDisk(const store::MapRecord& r);
  // The compressor's job (map_compress.cpp): the map's dem.tif from its raw files, then its
  // record's storage, its disk charge and the raw files' removal.
  void compressElevation(const std::string& id, const std::function<bool()>& cancelled);
  // Drops what was read from a map's elevation file and kept (its stored header, its DEMs at
  // coverage cell sizes), once that file has changed (the COG replaced the raw VRT); a read begun
  // before is not kept either (invalidations_).
  void forgetStoredElevation(const std::string& id);
  // The map's cells with data (1 where its height is not NaN), one byte a cell: the loaded map's,
  // else read from the stored DEM kValidBandRows rows at a time (the heights of one band in memory).
  std::vector<std::uint8_t> validCells(const std::string& mapId, const GridGeometry& g);
  static constexpr int kValidBandRows = 512;
  // What a map's tiles need of its record and folder, none of which changes after the import (a map
  // is immutable; a rename changes neither): its tile grid and, for a map stored as its pyramid,
  // its ramp. Read once per map (a SQLite read and a stat a tile were a twentieth of a cold tile's
  // CPU); the last 16 maps are kept (about 100 bytes each), a removed map's dropped. Throws
  // ApiError 404 (field "id") for an unknown map.
  struct StoredTiles {
    std::string id;
    maps::TileGrid grid;
    bool pyramid = false;     // dem.tif is the COG and classes.tif the class pyramid
    maps::ColourRange ramp;   // the pyramid's elevation ramp (the record's colour_range)
  };
  std::shared_ptr<const StoredTiles> storedTiles(const std::string& id);
  std::shared_ptr<const StoredTiles> cachedStoredTiles(const std::string& id);  // null when not kept
  // Writes the PDM's files (`write` fills the staging folder) and its row, charged to the map.
  store::PdmRecord storePdm(const std::string& mapId, const std::string& name, const nlohmann::json& meta,
                            const std::function<void(const std::string& staging)>& write, const std::string& by);

  store::Database& db_;
  store::DataDir& dir_;
  std::int64_t maxCells_;
  std::atomic<std::int64_t> backgroundCells_{kDefaultBackgroundCells};
  std::atomic<std::int64_t> wholeLayerCells_{kDefaultWholeLayerCells};
  mutable std::mutex mutex_;  // guards the map caches and jail_
  jail::JailConfig jail_;
  LayerCache layers_;
  std::list<std::shared_ptr<const MapData>> cache_;  // most recent first, a few maps
  std::list<std::pair<std::string, std::shared_ptr<const terrain::Dem>>> cellCache_;
  std::list<std::pair<std::string, std::shared_ptr<const maps::DemHeader>>> headerCache_;  // most recent first
  std::list<std::shared_ptr<const StoredTiles>> tilesCache_;  // most recent first
  // Maps removed or their elevation file changed: what was read before is not cached (a header
  // read from a raw VRT, a removed map's record), only returned.
  std::uint64_t invalidations_ = 0;
  std::list<std::pair<std::string, std::shared_ptr<const Raster<float>>>> massCache_;  // most recent first
  // `key`: the PDM's id and version tag (pdmVersionTag).
  void keepMass(const std::string& key, std::shared_ptr<const Raster<float>> mass);
  // Last: destroyed first, so its thread ends before anything it uses.
  std::unique_ptr<ElevationCompressor> compressor_;
};

}  // namespace rover::api
