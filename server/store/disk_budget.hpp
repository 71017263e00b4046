#pragma once
// Disk budgets (issue 22: a 6.6 KB upload and 12 PDM requests filled a 2 GB disk). Everything the
// server stores is charged here when it is committed and released when it is deleted:
//   per map:  its PDMs, its cached layer files and the results of missions on it
//   globally: all of that, plus the maps' own DEMs and the studies' databases.
// Past a budget the write is refused before the object becomes visible: too_large when one object
// is larger than a whole per-map budget (it could never fit), else disk_budget_full naming the budget and what fills it. Totals are kept incrementally (a charge is O(1)); they are
// counted from the files once at start-up (recountDiskUse).
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>

#include "server/store/data_dir.hpp"

namespace rover::store {

class Database;

const char* diskUseName(DiskUse use);  // "map", "PDM", "layer file", "mission result", "study"

struct DiskBudgetLimits {
  static constexpr std::uint64_t kUnlimited = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t globalBytes = kUnlimited;
  std::uint64_t perMapBytes = kUnlimited;
};

class DiskBudget {
 public:
  void setLimits(const DiskBudgetLimits& limits);
  DiskBudgetLimits limits() const;

  // Charges `bytes` of `use` under `key` (a stored folder or file; a key charged again replaces
  // its old size) to map `mapId` ("" for none) and to the global total. Throws OverBudget (too_large or
  // disk_budget_full, `field` in the error) and charges nothing when that would pass a budget.
  void charge(const std::string& key, DiskUse use, const std::string& mapId, std::uint64_t bytes,
              const std::string& field = "");
  // Records without a check: what is on disk already (start-up).
  void record(const std::string& key, DiskUse use, const std::string& mapId, std::uint64_t bytes);
  // Throws OverBudget disk_budget_full when the budget `use` would be charged to is already full, so a request
  // whose output cannot be stored is refused before it costs anything.
  void requireRoom(DiskUse use, const std::string& mapId, const std::string& field = "") const;
  void release(const std::string& key);

  std::uint64_t used() const;
  std::uint64_t usedByMap(const std::string& mapId) const;

 private:
  struct Item {
    DiskUse use;
    std::string mapId;
    std::uint64_t bytes = 0;
  };
  static bool perMap(DiskUse use) { return use == DiskUse::Pdm || use == DiskUse::Layer || use == DiskUse::Result; }
  void putLocked(const std::string& key, Item item);  // replaces what `key` held
  void removeLocked(const std::string& key);

  mutable std::mutex mutex_;
  DiskBudgetLimits limits_;
  std::unordered_map<std::string, Item> items_;
  std::unordered_map<std::string, std::uint64_t> byMap_;  // per-map uses only
  std::uint64_t total_ = 0;
};

// Bytes of the regular files under `path` (a file: its size; absent: 0).
std::uint64_t bytesUnder(const std::string& path);

// Start-up: charges what is stored under DATA/maps/ID (the DEM; layers/ is the LayerCache's),
// DATA/pdms/ID and DATA/missions/ID (to their maps, from the database) and DATA/studies/ID.
void recountDiskUse(const DataDir& dir, Database& db);

// 90 % of the size of the file system holding `root` (unlimited if it cannot be read).
std::uint64_t defaultDiskBudget(const std::string& root);

// "12.3 MB": sizes in messages.
std::string megabytes(std::uint64_t bytes);

}  // namespace rover::store
