#include "server/store/disk_budget.hpp"

#include <sys/statvfs.h>

#include <cstdio>
#include <filesystem>

#include "server/store/database.hpp"

namespace fs = std::filesystem;

namespace rover::store {

const char* diskUseName(DiskUse use) {
  switch (use) {
    case DiskUse::Map: return "map";
    case DiskUse::Pdm: return "PDM";
    case DiskUse::Layer: return "layer file";
    case DiskUse::Result: return "mission result";
    case DiskUse::Study: return "study";
  }
  return "file";
}

std::string megabytes(std::uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MB", static_cast<double>(bytes) / 1e6);
  return buf;
}

void DiskBudget::setLimits(const DiskBudgetLimits& limits) {
  std::lock_guard lock(mutex_);
  limits_ = limits;
}

DiskBudgetLimits DiskBudget::limits() const {
  std::lock_guard lock(mutex_);
  return limits_;
}

void DiskBudget::removeLocked(const std::string& key) {
  auto it = items_.find(key);
  if (it == items_.end()) return;
  total_ -= it->second.bytes;
  if (perMap(it->second.use)) {
    auto m = byMap_.find(it->second.mapId);
    m->second -= it->second.bytes;
    if (m->second == 0) byMap_.erase(m);
  }
  items_.erase(it);
}

void DiskBudget::putLocked(const std::string& key, Item item) {
  removeLocked(key);
  total_ += item.bytes;
  if (perMap(item.use)) byMap_[item.mapId] += item.bytes;
  items_[key] = std::move(item);
}

void DiskBudget::charge(const std::string& key, DiskUse use, const std::string& mapId, std::uint64_t bytes,
                        const std::string& field) {
  std::lock_guard lock(mutex_);
  // What `key` holds now is replaced, so it does not count against its own new size.
  std::uint64_t old = 0, oldOfMap = 0;
  if (auto it = items_.find(key); it != items_.end()) {
    old = it->second.bytes;
    if (perMap(it->second.use) && it->second.mapId == mapId) oldOfMap = it->second.bytes;
  }
  const std::string what = diskUseName(use);
  if (perMap(use)) {
    if (bytes > limits_.perMapBytes)
      throw OverBudget(Refusal::TooLarge,
                       "the " + what + " would take " + megabytes(bytes) +
                           " on disk, more than a map's whole disk budget of " + megabytes(limits_.perMapBytes),
                       field, false);
    const auto m = byMap_.find(mapId);
    const std::uint64_t ofMap = m == byMap_.end() ? 0 : m->second;
    if (ofMap - oldOfMap + bytes > limits_.perMapBytes)
      throw OverBudget(Refusal::DiskBudgetFull,
                       "the map's disk budget is full: its PDMs, layer files and mission results take " +
                           megabytes(ofMap) + " of " + megabytes(limits_.perMapBytes) + " and the " + what +
                           " needs " + megabytes(bytes) + "; delete some of its PDMs or missions",
                       field, false);
  }
  if (total_ - old + bytes > limits_.globalBytes)
    throw OverBudget(Refusal::DiskBudgetFull,
                     "the server's disk budget is full: " + megabytes(total_) + " of " +
                         megabytes(limits_.globalBytes) + " used and the " + what + " needs " + megabytes(bytes) +
                         "; delete maps, missions or studies",
                     field, true);
  putLocked(key, {use, mapId, bytes});
}

void DiskBudget::record(const std::string& key, DiskUse use, const std::string& mapId, std::uint64_t bytes) {
  std::lock_guard lock(mutex_);
  putLocked(key, {use, mapId, bytes});
}

void DiskBudget::requireRoom(DiskUse use, const std::string& mapId, const std::string& field) const {
  std::lock_guard lock(mutex_);
  if (perMap(use)) {
    const auto m = byMap_.find(mapId);
    if (m != byMap_.end() && m->second >= limits_.perMapBytes)
      throw OverBudget(Refusal::DiskBudgetFull,
                       "the map's disk budget is full: its PDMs, layer files and mission results take " +
                           megabytes(m->second) + " of " + megabytes(limits_.perMapBytes) +
                           "; delete some of its PDMs or missions",
                       field, false);
  }
  if (total_ >= limits_.globalBytes)
    throw OverBudget(Refusal::DiskBudgetFull,
                     "the server's disk budget is full: " + megabytes(total_) + " of " +
                         megabytes(limits_.globalBytes) + " used; delete maps, missions or studies",
                     field, true);
}

void DiskBudget::release(const std::string& key) {
  std::lock_guard lock(mutex_);
  removeLocked(key);
}

std::uint64_t DiskBudget::used() const {
  std::lock_guard lock(mutex_);
  return total_;
}

std::uint64_t DiskBudget::usedByMap(const std::string& mapId) const {
  std::lock_guard lock(mutex_);
  const auto m = byMap_.find(mapId);
  return m == byMap_.end() ? 0 : m->second;
}

std::uint64_t bytesUnder(const std::string& path) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return fs::file_size(path, ec);
  std::uint64_t total = 0;
  for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code fec;
    if (it->is_regular_file(fec)) {
      const auto size = it->file_size(fec);
      if (!fec) total += size;
    }
  }
  return total;
}

std::uint64_t defaultDiskBudget(const std::string& root) {
  struct statvfs fsStats {};
  if (::statvfs(root.c_str(), &fsStats) != 0) return DiskBudgetLimits::kUnlimited;
  const double size = static_cast<double>(fsStats.f_blocks) * static_cast<double>(fsStats.f_frsize);
  return static_cast<std::uint64_t>(size * 0.9);
}

void recountDiskUse(const DataDir& dir, Database& db) {
  DiskBudget& budget = dir.budget();
  std::error_code ec;
  for (const auto& map : fs::directory_iterator(fs::path(dir.root()) / "maps", ec)) {
    if (!map.is_directory()) continue;
    std::uint64_t bytes = 0;  // the DEM and anything beside it; layers/ is LayerCache's
    std::error_code fec;
    for (const auto& f : fs::directory_iterator(map.path(), fec))
      if (f.path().filename() != "layers") bytes += bytesUnder(f.path().string());
    budget.record(map.path().string(), DiskUse::Map, map.path().filename().string(), bytes);
  }
  for (const auto& pdm : fs::directory_iterator(fs::path(dir.root()) / "pdms", ec)) {
    const auto rec = db.getPdm(pdm.path().filename().string());
    budget.record(pdm.path().string(), DiskUse::Pdm, rec ? rec->mapId : std::string(), bytesUnder(pdm.path().string()));
  }
  for (const auto& mission : fs::directory_iterator(fs::path(dir.root()) / "missions", ec)) {
    const auto rec = db.getMission(mission.path().filename().string());
    budget.record(mission.path().string(), DiskUse::Result, rec ? rec->mapId : std::string(),
                  bytesUnder(mission.path().string()));
  }
  for (const auto& study : fs::directory_iterator(fs::path(dir.root()) / "studies", ec))
    budget.record(study.path().string(), DiskUse::Study, "", bytesUnder(study.path().string()));
}

}  // namespace rover::store
