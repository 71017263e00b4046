#pragma once
// Metadata of maps, PDMs and missions in SQLite (WAL), rasters and results as files beside it
// (issue: server, "Mission manager and storage"). Thread-safe: one connection behind a mutex; every
// write is one transaction, so a crash (even kill -9) leaves either the old or the new row.
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/store/run_status.hpp"

struct sqlite3;

namespace rover::store {

struct MapRecord {
  std::string id;
  std::string name;
  std::string createdAt;  // ISO 8601 UTC
  nlohmann::json meta;    // size, cell size, CRS, elevation range, class percentages, files
  long long version = 1;  // 1 when imported, +1 per rename (issue 26)
};

struct PdmRecord {
  std::string id;
  std::string mapId;
  std::string name;
  std::string createdAt;
  nlohmann::json meta;  // kind (gaussians | random | raster), components, files
  long long version = 1;  // 1 when created, +1 per saved change (issue 26)
};

// A map's keep-out zones as saved: a FeatureCollection whose features carry their ids ("z1", ...)
// and their own version (properties.version); `version` counts saves of the set, 0 = never saved.
struct ZoneSet {
  nlohmann::json body;
  long long version = 0;
  long long nextZone = 1;  // the number of the next zone id handed out
};

// A compare-and-set write: done, refused because the stored version is not the one named (the
// caller answers 412 with the current object), or the object is gone.
enum class Cas { Done, Stale, Missing };

// A map rename (Database::renameMap): its compare-and-set outcome; when the version matched but
// another map already has the name, `takenBy` is that map's id and nothing was written.
struct MapRename {
  Cas cas = Cas::Missing;
  std::string takenBy;
};

// One saved version of a PDM ("pdm", its id) or of a map's zone set ("zones", the map id).
struct HistoryEntry {
  long long version = 0;
  std::string by, at;
  nlohmann::json body;  // null in listings
};
// The saved versions kept per object: the newest 50 (older ones are dropped on write).
inline constexpr long long kHistoryPerObject = 50;

struct MissionRecord {
  std::string id;
  std::string mapId;
  std::string pdmId;    // "" when none
  std::string planner;
  nlohmann::json spec;  // the request as accepted (rovers, params)
  RunStatus status = RunStatus::Queued;
  std::string message;  // failure / interruption reason
  std::string createdAt, startedAt, finishedAt;
  nlohmann::json metrics;  // final metrics (object), null until finished
  std::string label;       // the operator's name for the run (the request's "name", editable)
  long long version = 1;   // +1 per label change (issue 26)
  // Read only, from the maps / PDMs tables: "" once the map or PDM is deleted.
  std::string mapName, pdmName;
};

// A full disk: every write throws StorageFull (data_dir.hpp) and leaves the old row.
// So that final mission statuses and deletes (which free space) still commit when the disk is
// full, the database keeps two reserves of disk in files beside it (PATH.reserve-status,
// PATH.reserve-delete): such a write that finds the disk full gives its reserve back and retries
// once; every later write takes the reserves again when there is room. A start on a full disk
// (no room for SQLite's WAL index) opens in exclusive locking mode, which keeps the index in memory.
class Database {
 public:
  static constexpr long kStatusReserveBytes = 256 << 10, kDeleteReserveBytes = 1 << 20;

  // Opens or creates the database file and its schema; throws std::runtime_error on failure.
  explicit Database(const std::string& path);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  // Inserts the map under a name no other map has: a taken name gets the first free " (k)",
  // k = 2, 3, … (issue 27: two uploads of one PDS3 pair both listed as "megt90n000cb.lbl"), written
  // back to `m.name`. Unique in the catalog, not only in one list: the API, the page and the
  // exports name one map the same way.
  void insertMap(MapRecord& m);
  void insertMap(const MapRecord& m) {
    MapRecord copy = m;
    insertMap(copy);
  }
  std::optional<MapRecord> getMap(const std::string& id);
  // Listings page in SQL (LIMIT/OFFSET): `limit` < 0 means all, `offset` rows are skipped.
  std::vector<MapRecord> listMaps(long long limit = -1, long long offset = 0);  // oldest first
  long long countMaps();
  // Sets the map's meta.storage (how its elevation is stored: raw while its COG is written, issue
  // 24), its version unchanged (the map's content is the same); false when the map is gone.
  bool setMapStorage(const std::string& id, const nlohmann::json& storage);
  bool deleteMap(const std::string& id);  // also deletes its PDMs' rows; returns false if absent
  // The rename of a client that read version `expected` (issue 26): the name stays unique in the
  // catalog (as insertMap keeps it), so a name another map has is refused, not suffixed: the
  // operator chose it.
  MapRename renameMap(const std::string& id, const std::string& name, long long expected);
  // A map's keep-out zones (a GeoJSON FeatureCollection, local frame), replacing any before; false
  // when the map does not exist. Deleted with the map.
  bool setZones(const std::string& mapId, const nlohmann::json& zones);
  std::optional<nlohmann::json> getZones(const std::string& mapId);  // nullopt: never set
  // The versioned zone set (issue 26); nullopt when never saved.
  std::optional<ZoneSet> getZoneSet(const std::string& mapId);
  // Saves `set.body` as version expected+1 when the stored version is `expected` (0: none stored
  // yet), with a history entry by `by`; one transaction.
  Cas putZoneSet(const std::string& mapId, const ZoneSet& set, long long expected, const std::string& by);

  void insertPdm(const PdmRecord& p, const std::string& by = "");  // with its history entry, version 1
  std::optional<PdmRecord> getPdm(const std::string& id);
  std::vector<PdmRecord> listPdms(const std::string& mapId, long long limit = -1, long long offset = 0);
  long long countPdms(const std::string& mapId);
  bool deletePdm(const std::string& id);
  // Saves p.name and p.meta as version expected+1 when the stored version is `expected`, with a
  // history entry (`body`) by `by`; one transaction. `before` runs inside it once the version
  // matched (the PDM's files are written there, so a refused write never touches them).
  Cas updatePdm(const PdmRecord& p, long long expected, const nlohmann::json& body, const std::string& by,
                const std::function<void()>& before = {});
  // A history entry written on its own (tests; writes above record theirs in their transaction).
  void recordHistory(const std::string& kind, const std::string& objectId, long long version,
                     const nlohmann::json& body, const std::string& by);
  std::vector<HistoryEntry> history(const std::string& kind, const std::string& objectId);  // newest first
  std::optional<HistoryEntry> historyVersion(const std::string& kind, const std::string& objectId, long long version);

  void insertMission(const MissionRecord& m);
  std::optional<MissionRecord> getMission(const std::string& id);
  std::vector<MissionRecord> listMissions(long long limit = -1, long long offset = 0);  // newest first
  long long countMissions();
  // Updates status and message; sets startedAt when status becomes running and finishedAt for
  // a final status; stores metrics when given.
  void updateMission(const std::string& id, RunStatus status, const std::string& message,
                     const nlohmann::json& metrics = nullptr);
  bool setMissionLabel(const std::string& id, const std::string& label);  // false if absent
  // The label change of a client that read version `expected` (issue 26).
  Cas relabelMission(const std::string& id, const std::string& label, long long expected);
  bool deleteMission(const std::string& id);                                // false if absent
  // After a restart: every queued or running mission becomes interrupted. Returns how many.
  int markUnfinishedInterrupted();

  // A named counter kept across restarts (the event stream's last sequence number).
  long long counter(const std::string& name);
  void setCounter(const std::string& name, long long value);

 private:
  struct Reserve {
    std::string path;  // empty for an in-memory database
    long bytes = 0;
    bool held = false;
  };
  void open(const std::string& path, bool exclusive);
  // Runs `write` (caller holds mutex_); on StorageFull releases `r` and runs it again.
  template <class F>
  auto withReserve(Reserve& r, F&& write) -> decltype(write());
  static bool release(Reserve& r);  // true if its file was there to remove
  void ensureReserves();            // best effort: (re)creates them when there is room
  // Runs `body` in one BEGIN IMMEDIATE .. COMMIT (caller holds mutex_); rolls back on a throw.
  template <class F>
  auto transaction(F&& body) -> decltype(body());
  void recordHistoryLocked(const std::string& kind, const std::string& objectId, long long version,
                           const std::string& body, const std::string& by);

  sqlite3* db_ = nullptr;
  std::mutex mutex_;
  Reserve statusReserve_, deleteReserve_;
};

// Current time as ISO 8601 UTC with milliseconds, e.g. 2026-11-23T08:00:00.123Z.
std::string nowIso();

}  // namespace rover::store
