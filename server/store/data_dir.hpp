#pragma once
// The server's data directory: rasters and results as files, written atomically (temp + rename),
// so a crash never leaves a half-written file or folder visible (issue: server, storage).
//   DATA/roverplan.db     SQLite metadata (Database)
//   DATA/maps/ID/         one folder per map (source DEM, cached layers)
//   DATA/pdms/ID/         one folder per PDM (components, mass raster)
//   DATA/missions/ID/     one folder per mission (result.json, result.geojson, result.csv)
//   DATA/tmp/             uploads in flight and folders being built; emptied at start-up
#include <memory>
#include <optional>
#include <string>

#include "server/errors/domain_error.hpp"

namespace rover::store {

// A write failed because the disk (or the file size limit) is full: refused insufficient_storage,
// with a message that names what could not be stored but no server path.
class StorageFull : public DomainError {
 public:
  explicit StorageFull(const std::string& what)
      : DomainError(Refusal::InsufficientStorage,
                    "the server's disk is full: " + what + "; free space or try again later") {}

 protected:
  StorageFull(Refusal code, const std::string& message, const std::string& field)
      : DomainError(code, message, field) {}
};

// Beyond a disk budget (DiskBudget, server/store/disk_budget.hpp): a StorageFull, so a mission or
// study that meets it fails as on a full disk; refused disk_budget_full, or too_large for one
// object no per-map budget could hold.
class OverBudget : public StorageFull {
 public:
  OverBudget(Refusal code, const std::string& message, const std::string& field, bool serverWide)
      : StorageFull(code, message, field), serverWide_(serverWide) {}
  // The global budget is full (not only the map's): freeing any map's files makes room.
  bool serverWide() const { return serverWide_; }

 private:
  bool serverWide_;
};

// What a stored folder is, for the disk budgets.
enum class DiskUse { Map, Pdm, Layer, Result, Study };
struct DiskCharge {
  DiskUse use;
  std::string mapId;  // "" for none (studies)
  std::string field;  // named in a refusal
};
class DiskBudget;

// True for the errno values of a full disk or an exceeded size limit (ENOSPC, EDQUOT, EFBIG).
bool isStorageFullErrno(int err);

class DataDir {
 public:
  // Creates the layout if missing; throws std::runtime_error if the folder is not writable. A
  // folder on a full disk is accepted (startedFull() says so): reads work and writes are refused until
  // space frees, so a restart with a full disk still starts.
  explicit DataDir(std::string root);
  ~DataDir();
  DataDir(const DataDir&) = delete;
  DataDir& operator=(const DataDir&) = delete;
  bool startedFull() const { return startedFull_; }
  // What is stored, against the disk budgets (unlimited until setLimits).
  DiskBudget& budget() const { return *budget_; }
  const std::string& root() const { return root_; }
  std::string databasePath() const;
  std::string mapDir(const std::string& id) const;
  std::string pdmDir(const std::string& id) const;
  std::string missionDir(const std::string& id) const;
  std::string tmpDir() const;

  // A new random id: 16 lowercase hex characters.
  static std::string newId();
  // A fresh empty folder under tmp/ to build something in before commitDir().
  std::string stagingDir() const;
  // Atomically moves a staged folder to its final place (rename); throws if the target exists.
  // With a charge, the staged folder's bytes are charged to the disk budgets first (OverBudget,
  // and nothing moved, when they do not fit) under the key `finalDir`.
  void commitDir(const std::string& staged, const std::string& finalDir,
                 const std::optional<DiskCharge>& charge = std::nullopt) const;
  // Removes a stored folder or file and releases its charge.
  void remove(const std::string& path) const;
  // Writes bytes to `path` atomically (temp file in the same folder, fsync, rename). A full disk
  // throws StorageFull (and leaves nothing behind). `durable` false skips both fsyncs, for files
  // that can be made again (the layer cache's tiles: two fsyncs were 8 ms a tile, p50, on this
  // machine, holding a work-pool thread idle); a crash may then leave such a file empty, and the
  // layer cache drops empty files when it starts.
  static void writeFileAtomic(const std::string& path, const std::string& bytes, bool durable = true);
  // The whole file when it is at most `maxBytes` long; nullopt when it is absent, larger, or cannot
  // be read (the caller has another way to the bytes: e.g. a tile removed by the layer cache
  // meanwhile is rendered again). With CachedOnly, also nullopt when any of its pages is not in the
  // page cache (preadv2 RWF_NOWAIT), so an io thread never waits for the disk; a filesystem that
  // cannot tell reads it plainly.
  enum class Read { Any, CachedOnly };
  static std::optional<std::string> readFileUpTo(const std::string& path, std::uint64_t maxBytes,
                                                 Read how = Read::Any);
  // Removes a folder and everything in it (no error if absent).
  static void removeTree(const std::string& path);
  // fsyncs the file `path` (throws StorageFull or std::runtime_error naming it, for the log), and
  // the folder `dir` best effort (some filesystems refuse fsync on a directory).
  static void flushFile(const std::string& path);
  static void flushDir(const std::string& dir);
  // Empties tmp/ (start-up: whatever was in flight when the server died is discarded).
  void cleanTmp() const;

 private:
  std::string root_;
  bool startedFull_ = false;
  std::unique_ptr<DiskBudget> budget_;
};

}  // namespace rover::store
