#include "server/api/layer_cache.hpp"

#include <algorithm>
#include <filesystem>
#include <vector>

namespace rover::api {

namespace fs = std::filesystem;

namespace {
// The map a layer file belongs to: maps/ID/layers/FILE.
std::string mapOf(const std::string& path) { return fs::path(path).parent_path().parent_path().filename().string(); }
}  // namespace

LayerCache::LayerCache(const std::string& mapsRoot, std::uint64_t capBytes,
                       const std::function<bool(const std::string&)>& stale, store::DiskBudget* budget)
    : budget_(budget), cap_(capBytes) {
  std::vector<std::pair<fs::file_time_type, std::pair<std::string, std::uint64_t>>> found;
  std::error_code ec;
  for (const auto& map : fs::directory_iterator(mapsRoot, ec)) {
    std::error_code ec2;
    for (const auto& f : fs::directory_iterator(map.path() / "layers", ec2)) {
      std::error_code ec3;
      if (!f.is_regular_file(ec3)) continue;
      // Tiles are written without fsync (DataDir::writeFileAtomic, durable = false): a crash can
      // leave one empty, and an empty file is no tile.
      if ((stale && stale(f.path().filename().string())) || f.file_size(ec3) == 0) {
        fs::remove(f.path(), ec3);
        continue;
      }
      found.push_back({f.last_write_time(ec3), {f.path().string(), f.file_size(ec3)}});
    }
  }
  std::sort(found.begin(), found.end());
  std::lock_guard lock(mutex_);
  for (const auto& [when, file] : found) {
    addLocked(file.first, file.second);
    if (budget_) budget_->record(file.first, store::DiskUse::Layer, mapOf(file.first), file.second);
  }
  evictLocked("");
}

void LayerCache::addLocked(const std::string& path, std::uint64_t size) {
  auto [it, fresh] = entries_.try_emplace(path);
  if (fresh) {
    it->second.use = byUse_.insert(byUse_.end(), &it->first);
  } else {
    total_ -= it->second.size;
    byUse_.splice(byUse_.end(), byUse_, it->second.use);
  }
  it->second.size = size;
  total_ += size;
}

void LayerCache::eraseLocked(Entries::iterator it) {
  total_ -= it->second.size;
  byUse_.erase(it->second.use);
  entries_.erase(it);
}

bool LayerCache::evictOldestLocked(const std::string& keep, const std::string& ofMap) {
  for (const std::string* path : byUse_) {
    if (*path == keep || (!ofMap.empty() && mapOf(*path) != ofMap)) continue;
    std::error_code ec;
    fs::remove(*path, ec);
    if (budget_) budget_->release(*path);
    eraseLocked(entries_.find(*path));
    return true;
  }
  return false;
}

void LayerCache::evictLocked(const std::string& keep) {
  while (total_ > cap_ && evictOldestLocked(keep)) {
  }
}

void LayerCache::chargeLocked(const std::string& path, std::uint64_t size) {
  if (!budget_) return;
  for (;;) {
    try {
      budget_->charge(path, store::DiskUse::Layer, mapOf(path), size, "layer");
      return;
    } catch (const store::OverBudget& e) {
      // A cache makes room by forgetting (the map's own files when its budget is full, any when
      // the server's is); what cannot fit even then is refused.
      if (e.refusal() == Refusal::DiskBudgetFull && evictOldestLocked(path, e.serverWide() ? std::string() : mapOf(path))) continue;
      std::error_code ec;
      fs::remove(path, ec);
      throw;
    }
  }
}

bool LayerCache::tryUse(const std::string& path) {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  auto it = entries_.find(path);
  if (it == entries_.end()) return false;
  byUse_.splice(byUse_.end(), byUse_, it->second.use);
  return true;
}

std::string LayerCache::get(const std::string& path, const std::function<void(const std::string&)>& make) {
  std::shared_ptr<std::mutex> once;
  {
    std::lock_guard lock(mutex_);
    if (auto it = entries_.find(path); it != entries_.end()) {
      byUse_.splice(byUse_.end(), byUse_, it->second.use);
      return path;
    }
    auto& m = making_[path];
    if (!m) m = std::make_shared<std::mutex>();
    once = m;
  }
  std::lock_guard making(*once);  // a second request for the same file waits here, then finds it
  auto release = [&] {
    std::lock_guard lock(mutex_);
    if (auto it = making_.find(path); it != making_.end() && it->second == once && once.use_count() <= 2)
      making_.erase(it);
  };
  {
    std::unique_lock lock(mutex_);
    if (auto it = entries_.find(path); it != entries_.end()) {
      byUse_.splice(byUse_.end(), byUse_, it->second.use);
      lock.unlock();
      release();
      return path;
    }
  }
  try {
    make(path);
  } catch (...) {
    release();
    throw;
  }
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  try {
    std::lock_guard lock(mutex_);
    chargeLocked(path, ec ? 0 : size);
    addLocked(path, ec ? 0 : size);
    evictLocked(path);
  } catch (...) {
    release();
    throw;
  }
  release();
  return path;
}

void LayerCache::forgetUnder(const std::string& dir) {
  std::string prefix = dir;
  if (!prefix.empty() && prefix.back() != '/') prefix += '/';
  std::lock_guard lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (it->first.rfind(prefix, 0) == 0) {
      if (budget_) budget_->release(it->first);
      eraseLocked(it++);
    } else {
      ++it;
    }
  }
}

void LayerCache::discardUnder(const std::string& dir,
                              const std::function<bool(const std::string& fileName)>& unreachable) {
  std::string prefix = dir;
  if (!prefix.empty() && prefix.back() != '/') prefix += '/';
  std::lock_guard lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end();) {
    const std::string& path = it->first;
    if (path.rfind(prefix, 0) == 0 && path.find('/', prefix.size()) == std::string::npos &&
        unreachable(path.substr(prefix.size()))) {
      std::error_code ec;
      fs::remove(path, ec);
      if (budget_) budget_->release(path);
      eraseLocked(it++);
    } else {
      ++it;
    }
  }
}

std::uint64_t LayerCache::bytes() const {
  std::lock_guard lock(mutex_);
  return total_;
}

}  // namespace rover::api
