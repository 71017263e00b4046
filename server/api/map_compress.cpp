// MapCatalog's compression of maps stored raw (issue 24): an import commits its map with the
// elevation as the server's float32 grid, its levels and a VRT (server/api/map_files.hpp
// kRawDemDir), so its first tiles come before the COG's ~10 s of CPU; the compressor
// (server/api/elevation_compressor.hpp) then writes dem.tif here, one map at a time.
#include <fcntl.h>
#include <unistd.h>

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

// Flushes `path` (a file or folder) to the disk: the COG must be durable before the raw files,
// the map's only other copy, go (as commitDir makes an import's files durable).
void flush(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path.string() + " to flush it");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot flush " + path.string());
}

}  // namespace

void MapCatalog::compressElevation(const std::string& id, const std::function<bool()>& cancelled) {
  const fs::path mapDir = dir_.mapDir(id);
  const fs::path raw = mapDir / kRawDemDir;
  // A deleted map is left alone (its folder is removed by remove(), never made again here).
  const auto rec = db_.getMap(id);
  if (!rec || cancelled()) return;
  std::error_code ec;
  const auto from = std::chrono::steady_clock::now();
  if (!fs::exists(mapDir / kDemFile, ec)) {
    if (!fs::exists(raw / kRawDemVrt, ec)) return;  // neither: not a map of ours to mend
    // Written as dem.tif.tmp in the map's folder and renamed into place (maps::writeDemCog's
    // atomic write): a reader sees the raw VRT or the whole COG, never a part. No folder is
    // created: if the map's folder went meanwhile, the write fails and nothing is left.
    storingGeoTiff([&] { maps::writeDemCogFromRaw((mapDir / kDemFile).string(), (raw / kRawDemVrt).string(), cancelled); });
  }
  flush(mapDir / kDemFile);
  flush(mapDir);
  // Both are on disk now: charged as they are until the raw files go.
  dir_.budget().record(mapDir.string(), store::DiskUse::Map, id, mapBytes(mapDir));
  const auto& m = rec->meta;
  const int overviews = m.contains("rows") && m.contains("cols")
                            ? maps::tileGridOf(m["rows"].get<int>(), m["cols"].get<int>()).nativeZoom
                            : 0;
  db_.setMapStorage(id, cogStorage(overviews));
  {
    // The header read from the VRT names its driver; the COG's is read afresh.
    std::lock_guard lock(mutex_);
    headerCache_.remove_if([&](const auto& e) { return e.first == id; });
  }
  // Readers that opened the VRT keep their files (open descriptors); one that opens it after this
  // finds dem.tif instead (readElevation).
  store::DataDir::removeTree(raw.string());
  dir_.budget().record(mapDir.string(), store::DiskUse::Map, id, mapBytes(mapDir));
  if (onStorageChanged) onStorageChanged(id);
  std::cerr << "compressed map " << id << ": dem.tif in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count() << " s" << std::endl;
}

int MapCatalog::resumeCompressions() {
  int queued = 0;
  for (const auto& m : db_.listMaps()) {
    const auto it = m.meta.find("storage");
    if (it == m.meta.end() || !it->is_object() || it->value("elevation", std::string()) != "raw") continue;
    compressor_->enqueue(m.id);
    ++queued;
  }
  return queued;
}

}  // namespace rover::api
