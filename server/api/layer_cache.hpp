#pragma once
// Rendered layer files (PNG overviews, GeoTIFF and float32 exports in DATA/maps/ID/layers/) kept
// as a cache with a size cap per data dir: when a new file takes the total past the cap, the least
// recently used files are deleted (issue 14: 40 distinct ?max= values once wrote 686 MB). Each file
// is produced once however many requests ask for it at the same time (a once-lock per file), and
// producing one blocks neither other layers nor other maps.
// With a DiskBudget the files are charged to their map (DiskUse::Layer): a new file that does not
// fit first evicts older ones (of any map), then is refused (OverBudget disk_budget_full or
// too_large, field "layer") and deleted.
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "server/store/disk_budget.hpp"

namespace rover::api {

class LayerCache {
 public:
  // Counts the layer files already under mapsRoot/*/layers/ (oldest first by modification time),
  // deleting those `stale` says no request can name any more (an older naming scheme).
  LayerCache(const std::string& mapsRoot, std::uint64_t capBytes,
             const std::function<bool(const std::string& fileName)>& stale = {},
             store::DiskBudget* budget = nullptr);

  // `path`, made by `make(path)` (which writes it atomically) unless it is there already. A file
  // larger than the cap on its own is still kept until the next one arrives.
  std::string get(const std::string& path, const std::function<void(const std::string&)>& make);
  // Whether `path` is cached, counting as a use; false as well when another thread holds the
  // cache (evicting, say): never waits and never makes the file, for an io thread's answer
  // (RouteOptions::quick), which then leaves the request to the pool.
  bool tryUse(const std::string& path);
  // Forgets the files under `dir` (a deleted map's folder).
  void forgetUnder(const std::string& dir);
  // Deletes the cached files under `dir` whose file name `unreachable` accepts (e.g. an edited or
  // deleted PDM's old versions, which no request can name any more) and releases their charge.
  // A file being made meanwhile is added after; it is evicted in its turn like any other.
  void discardUnder(const std::string& dir, const std::function<bool(const std::string& fileName)>& unreachable);

  std::uint64_t bytes() const;
  std::uint64_t capBytes() const { return cap_; }

 private:
  struct Entry {
    std::uint64_t size = 0;
    std::list<const std::string*>::iterator use;  // its place in byUse_
  };
  using Entries = std::unordered_map<std::string, Entry>;
  void addLocked(const std::string& path, std::uint64_t size);
  void eraseLocked(Entries::iterator it);
  void evictLocked(const std::string& keep);
  // Deletes the least recently used file but `keep` (of map `ofMap` when given); false when none is left.
  bool evictOldestLocked(const std::string& keep, const std::string& ofMap = "");
  // Charges a new file to the budget, evicting older files while it does not fit; throws
  // OverBudget (the file is deleted) when it cannot fit.
  void chargeLocked(const std::string& path, std::uint64_t size);

  store::DiskBudget* budget_;
  const std::uint64_t cap_;
  mutable std::mutex mutex_;  // guards everything below; never held while a file is made
  Entries entries_;
  // The cached files' paths (the keys of entries_, whose addresses a rehash keeps), least recently
  // used first: an eviction takes the front, a use moves a file to the back, both O(1) (a scan of
  // every file for the oldest, per eviction, held the lock for seconds with 50 k tiles cached).
  std::list<const std::string*> byUse_;
  std::unordered_map<std::string, std::shared_ptr<std::mutex>> making_;  // once-locks in use
  std::uint64_t total_ = 0;
};

}  // namespace rover::api
