// MapCatalog's compression of maps stored raw (issue 24): an import commits its map with the
// elevation as the server's float32 grid, its levels and a VRT (server/api/map_files.hpp
// kRawDemDir), so its first tiles come before the COG's ~10 s of CPU; the compressor
// (server/api/elevation_compressor.hpp) then writes dem.tif here, one map at a time.
#include <chrono>
#include <stdexcept>
#include <exception>
#include <iostream>
#include <filesystem>

#include "maps/dem_pyramid.hpp"
#include "maps/tile_grid.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/map_files.hpp"
#include "server/store/disk_budget.hpp"

namespace rover::api {

namespace fs = std::filesystem;

namespace {

// What a map's folder holds besides its layer cache (the budget's "map" bytes, as recountDiskUse
// counts them).
std::uint64_t mapBytes(const fs::path& mapDir) {
  std::uint64_t bytes = 0;
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(mapDir, ec))
    if (f.path().filename() != "layers") bytes += store::bytesUnder(f.path().string());
  return bytes;
}

}  // namespace

void MapCatalog::compressElevation(const std::string& id, const std::function<bool()>& cancelled) {
  const fs::path mapDir = dir_.mapDir(id);
  const fs::path raw = mapDir / kRawDemDir;
  const fs::path cog = mapDir / kDemFile;
  // A deleted map is left alone (its folder is removed by remove(), never made again here).
  const auto rec = db_.getMap(id);
  if (!rec || cancelled()) return;
  std::error_code ec;
  const auto from = std::chrono::steady_clock::now();
  // While the raw files are there they are the map's elevation: the COG is (re)written from them
  // whatever dem.tif holds (a dem.tif renamed into place before a power cut may hold nothing).
  if (!fs::exists(raw / kRawDemVrt, ec)) return;  // compressed already (or not a map of ours)
  // The disk budgets (server/store/disk_budget.hpp) see the COG before it is written: the map is
  // charged for its raw files and, until they go, for the COG too. Its size is known once it is
  // written, so room for the most it can take is reserved first: the raw files hold the same
  // levels uncompressed, and ZSTD stores a block it cannot shrink as it is (a few bytes a 128²
  // block), plus the TIFF's directories and block tables. A map's DEM is charged to the server's
  // budget only (the per-map one is its PDMs, layer files and results). When that does not fit,
  // OverBudget is thrown before anything is written: the map stays raw and the compressor tries
  // again later (ElevationCompressor's retries), when maps or missions may have been deleted.
  const std::uint64_t before = mapBytes(mapDir);
  const std::uint64_t rawBytes = store::bytesUnder(raw.string());
  const std::uint64_t cogBound = rawBytes + rawBytes / 64 + (std::uint64_t(64) << 10);
  try {
    dir_.budget().charge(mapDir.string(), store::DiskUse::Map, id, before + cogBound);
  } catch (const store::OverBudget& e) {
    // For the log: the charge's own words count the whole map, raw files and COG together.
    throw std::runtime_error("no room for its COG (up to " + store::megabytes(cogBound) + " beside its " +
                             store::megabytes(before) + "): " + e.what());
  }
  bool committed = false;
  struct Undo {  // until the record says "cog": no dem.tif beside the raw files, the charge as on disk
    MapCatalog& catalog;
    const std::string& id;
    const fs::path& mapDir;
    const fs::path& cog;
    const bool& committed;
    ~Undo() {
      if (committed) return;
      std::error_code ec;
      fs::remove(cog, ec);  // readers that opened it keep reading; the others read the raw VRT
      catalog.dir_.budget().record(mapDir.string(), store::DiskUse::Map, id, mapBytes(mapDir));
    }
  } undo{*this, id, mapDir, cog, committed};
  // Written as dem.tif.tmp in the map's folder and renamed into place (maps::writeDemCog's
  // atomic write, which removes its temporary files when it fails or is cancelled): a reader
  // sees the raw VRT or the whole COG, never a part. No folder is created: if the map's folder
  // went meanwhile, the write fails and nothing is left.
  storingGeoTiff([&] { maps::writeDemCogFromRaw(cog.string(), (raw / kRawDemVrt).string(), cancelled); });
  // On the disk before the raw files, the map's only other copy, go.
  store::DataDir::flushFile(cog.string());
  store::DataDir::flushDir(mapDir.string());
  // Both are on disk now: charged as they are (within the reservation, unless the bound was
  // beaten: then checked again) until the raw files go.
  dir_.budget().charge(mapDir.string(), store::DiskUse::Map, id, mapBytes(mapDir));
  const auto& m = rec->meta;
  const int overviews = m.contains("rows") && m.contains("cols")
                            ? maps::tileGridOf(m["rows"].get<int>(), m["cols"].get<int>()).nativeZoom
                            : 0;
  db_.setMapStorage(id, cogStorage(overviews));
  committed = true;
  // What was read from the raw files and kept (the header read from the VRT names its driver and
  // path) is read afresh from the COG.
  forgetStoredElevation(id);
  // Readers that opened the VRT keep their files (open descriptors); one that opens it after this
  // finds dem.tif instead (readElevation).
  store::DataDir::removeTree(raw.string());
  maps::forgetStoredRasters(raw.string());
  dir_.budget().record(mapDir.string(), store::DiskUse::Map, id, mapBytes(mapDir));
  if (onStorageChanged) onStorageChanged(id);
  std::cerr << "compressed map " << id << ": dem.tif in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count() << " s" << std::endl;
}

void MapCatalog::forgetStoredElevation(const std::string& id) {
  std::lock_guard lock(mutex_);
  headerCache_.remove_if([&](const auto& e) { return e.first == id; });
  cellCache_.remove_if([&](const auto& e) { return e.first.rfind(id + "@", 0) == 0; });
  ++invalidations_;  // a read begun before this is not kept (storedHeader, demAtCell)
}

int MapCatalog::resumeCompressions() {
  int queued = 0;
  for (const auto& m : db_.listMaps()) {
    const fs::path mapDir = dir_.mapDir(m.id);
    std::error_code ec;
    const auto it = m.meta.find("storage");
    if (it == m.meta.end() || !it->is_object() || it->value("elevation", std::string()) != "raw") {
      // A COG map whose raw files outlived a crash between its record and their removal.
      if (fs::exists(mapDir / kRawDemDir, ec) && fs::exists(mapDir / kDemFile, ec))
        store::DataDir::removeTree((mapDir / kRawDemDir).string());
      continue;
    }
    // A dem.tif beside the raw files is from a job that did not finish (renamed, maybe not yet
    // on disk): readers go back to the raw VRT until the job writes it again.
    // So are the temporary files of a write a crash cut short (maps::writeDemCog's).
    if (fs::exists(mapDir / kRawDemDir / kRawDemVrt, ec)) {
      const std::string tmp = std::string(kDemFile) + ".tmp";
      for (const std::string& f : {std::string(kDemFile), tmp, tmp + ".aux.xml", tmp + ".ovr.tmp"})
        fs::remove(mapDir / f, ec);
    }
    compressor_->enqueue(m.id);
    ++queued;
  }
  return queued;
}

}  // namespace rover::api
