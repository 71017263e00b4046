#include "server/store/database.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <utility>

#include "server/store/data_dir.hpp"
#include "server/store/sqlite_stmt.hpp"

// Durability choice: journal_mode=WAL with synchronous=NORMAL. Every write below is a single
// statement, i.e. one implicit transaction. In WAL mode a transaction is committed once its frames
// are appended to the -wal file with write(); with synchronous=NORMAL SQLite does not fsync at
// every commit, only at checkpoints. The data written by write() lives in the kernel's page cache,
// which survives the death of the process (crash, abort, kill -9): the next open replays the WAL.
// So a committed row is never lost to a process crash. Only a power loss / kernel panic can roll
// back the last few transactions (never corrupt the database) — an acceptable trade for a planning
// server whose missions are marked "interrupted" at restart anyway. Use synchronous=FULL if
// power-loss durability of the very last commit ever matters.

namespace rover::store {

namespace {

constexpr int kSchemaVersion = 3;

std::string dumpJson(const nlohmann::json& j, const char* what) {
  try {
    return j.dump();
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("database: cannot store ") + what + ": " + e.what());
  }
}

nlohmann::json parseJson(const Stmt& s, int col, const char* what) {
  if (s.isNull(col)) return nullptr;
  try {
    return nlohmann::json::parse(s.text(col));
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("database: corrupt ") + what + " JSON: " + e.what());
  }
}


// Version 1 of the schema. Later versions add a migrate step from N-1 in Database::Database.
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE IF NOT EXISTS maps(
  id         TEXT PRIMARY KEY,
  name       TEXT NOT NULL,
  created_at TEXT NOT NULL,
  meta       TEXT NOT NULL DEFAULT 'null'
);
CREATE TABLE IF NOT EXISTS pdms(
  id         TEXT PRIMARY KEY,
  map_id     TEXT NOT NULL REFERENCES maps(id) ON DELETE CASCADE,
  name       TEXT NOT NULL,
  created_at TEXT NOT NULL,
  meta       TEXT NOT NULL DEFAULT 'null'
);
CREATE INDEX IF NOT EXISTS pdms_by_map ON pdms(map_id);
-- map_id / pdm_id are plain text on purpose (no foreign key): a mission's record outlives its map.
CREATE TABLE IF NOT EXISTS missions(
  id          TEXT PRIMARY KEY,
  map_id      TEXT NOT NULL,
  pdm_id      TEXT NOT NULL DEFAULT '',
  planner     TEXT NOT NULL,
  spec        TEXT NOT NULL DEFAULT 'null',
  status      TEXT NOT NULL,
  message     TEXT NOT NULL DEFAULT '',
  created_at  TEXT NOT NULL,
  started_at  TEXT,
  finished_at TEXT,
  metrics     TEXT
);
CREATE INDEX IF NOT EXISTS missions_by_created ON missions(created_at DESC, id);
CREATE INDEX IF NOT EXISTS missions_by_status ON missions(status);
)sql";

MapRecord readMap(const Stmt& s) {
  return MapRecord{s.text(0), s.text(1), s.text(2), parseJson(s, 3, "map meta")};
}

PdmRecord readPdm(const Stmt& s) {
  return PdmRecord{s.text(0), s.text(1), s.text(2), s.text(3), parseJson(s, 4, "PDM meta")};
}

// Version 2: a mission's label, first the request's name.
constexpr const char* kMigrateV1toV2 = R"sql(
ALTER TABLE missions ADD COLUMN label TEXT NOT NULL DEFAULT '';
UPDATE missions SET label = COALESCE(json_extract(spec, '$.name'), '')
  WHERE json_valid(spec) AND json_type(spec, '$.name') = 'text';
)sql";

// Version 3: a map's keep-out zones (issue 13), one GeoJSON FeatureCollection per map, deleted
// with the map.
constexpr const char* kMigrateV2toV3 = R"sql(
CREATE TABLE IF NOT EXISTS zones(
  map_id     TEXT PRIMARY KEY REFERENCES maps(id) ON DELETE CASCADE,
  body       TEXT NOT NULL,
  updated_at TEXT NOT NULL
);
)sql";

// A mission row with the names of its map and PDM (empty once they are deleted).
constexpr const char* kMissionSelect =
    "SELECT m.id, m.map_id, m.pdm_id, m.planner, m.spec, m.status, m.message, m.created_at, "
    "m.started_at, m.finished_at, m.metrics, m.label, COALESCE(maps.name, ''), "
    "COALESCE(pdms.name, '') FROM missions m LEFT JOIN maps ON maps.id = m.map_id "
    "LEFT JOIN pdms ON pdms.id = m.pdm_id ";

// A status as an SQL string literal (the names hold no quote).
std::string sqlName(RunStatus s) {
  std::string out = "'";  // appended, not `"'" + name + "'"`: GCC 12 warns on that (-Wrestrict)
  out.append(enumName(s));
  out.push_back('\'');
  return out;
}

// The final statuses as an SQL list: 'succeeded', 'completed_with_warnings', ...
std::string finalStatusList() {
  std::string out;
  for (const auto& [s, name] : EnumNames<RunStatus>::table)
    if (isFinal(s)) out += (out.empty() ? "" : ", ") + sqlName(s);
  return out;
}

MissionRecord readMission(const Stmt& s) {
  MissionRecord m;
  m.id = s.text(0);
  m.mapId = s.text(1);
  m.pdmId = s.text(2);
  m.planner = s.text(3);
  m.spec = parseJson(s, 4, "mission spec");
  const std::string status = s.text(5);
  const auto parsed = parseEnum<RunStatus>(status);
  if (!parsed) throw std::runtime_error("database: mission " + m.id + " has an unknown status '" + status + "'");
  m.status = *parsed;
  m.message = s.text(6);
  m.createdAt = s.text(7);
  m.startedAt = s.text(8);
  m.finishedAt = s.text(9);
  m.metrics = parseJson(s, 10, "mission metrics");
  m.label = s.text(11);
  m.mapName = s.text(12);
  m.pdmName = s.text(13);
  return m;
}

}  // namespace

Database::Database(const std::string& path) {
  if (!path.empty() && path != ":memory:" && path.rfind("file:", 0) != 0) {
    statusReserve_ = {path + ".reserve-status", kStatusReserveBytes};
    deleteReserve_ = {path + ".reserve-delete", kDeleteReserveBytes};
  }
  try {
    open(path, false);
  } catch (const StorageFull&) {
    // A restart with a full disk: no room for the WAL index (-shm). Exclusive locking keeps it in
    // the process's memory, so reads work and the reserves stay for deletes; failing that, the
    // reserves give SQLite the room.
    try {
      open(path, true);
    } catch (const StorageFull&) {
      if (!release(deleteReserve_) && !release(statusReserve_)) throw;
      open(path, false);
    }
  }
  ensureReserves();
}

bool Database::release(Reserve& r) {
  if (r.path.empty()) return false;
  r.held = false;
  return ::unlink(r.path.c_str()) == 0;
}

void Database::ensureReserves() {
  for (Reserve* r : {&deleteReserve_, &statusReserve_}) {
    if (r->held || r->path.empty()) continue;
    const int fd = ::open(r->path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
    if (fd < 0) return;
    // Allocated blocks, not a sparse file: the point is that the space is really taken.
    const bool ok = ::posix_fallocate(fd, 0, r->bytes) == 0;
    ::close(fd);
    if (!ok) {
      ::unlink(r->path.c_str());
      return;
    }
    r->held = true;
  }
}

template <class F>
auto Database::withReserve(Reserve& r, F&& write) -> decltype(write()) {
  try {
    return write();
  } catch (const StorageFull&) {
    if (!release(r)) throw;
    return write();
  }
}

void Database::open(const std::string& path, bool exclusive) {
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX;
  if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    std::string msg = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw std::runtime_error("database: cannot open '" + path + "': " + msg);
  }
  try {
    sqlite3_extended_result_codes(db_, 1);
    exec(db_, "PRAGMA busy_timeout=5000");
    if (exclusive) exec(db_, "PRAGMA locking_mode=EXCLUSIVE");
    {
      Stmt s(db_, "PRAGMA journal_mode=WAL");
      const std::string mode = s.step() ? s.text(0) : std::string();
      // An in-memory database (":memory:") reports "memory"; a file must really be in WAL mode.
      if (mode != "wal" && mode != "memory")
        throw std::runtime_error("database: cannot enable WAL on '" + path + "' (journal mode " +
                                 mode + ")");
    }
    exec(db_, "PRAGMA synchronous=NORMAL");
    exec(db_, "PRAGMA foreign_keys=ON");

    // Schema creation / migration in one write transaction, so two processes opening a fresh file
    // at once cannot both initialise it.
    exec(db_, "BEGIN IMMEDIATE");
    try {
      exec(db_, "CREATE TABLE IF NOT EXISTS schema_version(version INTEGER NOT NULL)");
      long long version = 0;
      {
        Stmt s(db_, "SELECT MAX(version) FROM schema_version");
        if (s.step() && !s.isNull(0)) version = s.integer(0);
      }
      if (version > kSchemaVersion)
        throw std::runtime_error("database: '" + path + "' has schema version " +
                                 std::to_string(version) + ", newer than this server supports (" +
                                 std::to_string(kSchemaVersion) + ")");
      // A new file gets version 1, then every migration from N-1 to N in turn.
      exec(db_, kSchemaV1);
      if (version == 0) {
        Stmt s(db_, "INSERT INTO schema_version(version) VALUES (1)");
        s.run();
        version = 1;
      }
      if (version == 1) {
        exec(db_, kMigrateV1toV2);
        Stmt s(db_, "INSERT INTO schema_version(version) VALUES (2)");
        s.run();
        version = 2;
      }
      if (version == 2) {
        exec(db_, kMigrateV2toV3);
        Stmt s(db_, "INSERT INTO schema_version(version) VALUES (3)");
        s.run();
        version = 3;
      }
      exec(db_, "COMMIT");
    } catch (...) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  } catch (...) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw;
  }
}

Database::~Database() {
  if (db_ != nullptr) sqlite3_close_v2(db_);
}

// ---- maps -------------------------------------------------------------------------------------

void Database::insertMap(const MapRecord& m) {
  const std::string meta = dumpJson(m.meta, "map meta");
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_, "INSERT INTO maps(id, name, created_at, meta) VALUES (?1, ?2, ?3, ?4)");
  s.bind(1, m.id).bind(2, m.name).bind(3, m.createdAt).bind(4, meta).run();
}

std::optional<MapRecord> Database::getMap(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id, name, created_at, meta FROM maps WHERE id = ?1");
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return readMap(s);
}

std::vector<MapRecord> Database::listMaps(long long limit, long long offset) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id, name, created_at, meta FROM maps ORDER BY created_at ASC, id ASC LIMIT ?1 OFFSET ?2");
  s.bindInt(1, limit).bindInt(2, offset);
  std::vector<MapRecord> out;
  while (s.step()) out.push_back(readMap(s));
  return out;
}

long long Database::countMaps() {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT COUNT(*) FROM maps");
  return s.step() ? s.integer(0) : 0;
}

bool Database::deleteMap(const std::string& id) {
  std::lock_guard lock(mutex_);
  // The PDMs go with it through ON DELETE CASCADE, in the same statement (one transaction).
  ensureReserves();
  return withReserve(deleteReserve_, [&] {
    Stmt s(db_, "DELETE FROM maps WHERE id = ?1");
    s.bind(1, id).run();
    return sqlite3_changes(db_) > 0;
  });
}

bool Database::setZones(const std::string& mapId, const nlohmann::json& zones) {
  const std::string body = dumpJson(zones, "zones");
  std::lock_guard lock(mutex_);
  ensureReserves();
  // One statement: the row is written only while the map exists (a delete racing it wins).
  Stmt s(db_,
         "INSERT INTO zones(map_id, body, updated_at) SELECT ?1, ?2, ?3 WHERE EXISTS "
         "(SELECT 1 FROM maps WHERE id = ?1) ON CONFLICT(map_id) DO UPDATE SET "
         "body = excluded.body, updated_at = excluded.updated_at");
  s.bind(1, mapId).bind(2, body).bind(3, nowIso()).run();
  return sqlite3_changes(db_) > 0;
}

std::optional<nlohmann::json> Database::getZones(const std::string& mapId) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT body FROM zones WHERE map_id = ?1");
  s.bind(1, mapId);
  if (!s.step()) return std::nullopt;
  return parseJson(s, 0, "zones");
}

// ---- PDMs -------------------------------------------------------------------------------------

void Database::insertPdm(const PdmRecord& p) {
  const std::string meta = dumpJson(p.meta, "PDM meta");
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_, "INSERT INTO pdms(id, map_id, name, created_at, meta) VALUES (?1, ?2, ?3, ?4, ?5)");
  s.bind(1, p.id).bind(2, p.mapId).bind(3, p.name).bind(4, p.createdAt).bind(5, meta).run();
}

std::optional<PdmRecord> Database::getPdm(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id, map_id, name, created_at, meta FROM pdms WHERE id = ?1");
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return readPdm(s);
}

std::vector<PdmRecord> Database::listPdms(const std::string& mapId, long long limit, long long offset) {
  std::lock_guard lock(mutex_);
  Stmt s(db_,
         "SELECT id, map_id, name, created_at, meta FROM pdms WHERE map_id = ?1 "
         "ORDER BY created_at ASC, id ASC LIMIT ?2 OFFSET ?3");
  s.bind(1, mapId).bindInt(2, limit).bindInt(3, offset);
  std::vector<PdmRecord> out;
  while (s.step()) out.push_back(readPdm(s));
  return out;
}

long long Database::countPdms(const std::string& mapId) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT COUNT(*) FROM pdms WHERE map_id = ?1");
  s.bind(1, mapId);
  return s.step() ? s.integer(0) : 0;
}

bool Database::deletePdm(const std::string& id) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  return withReserve(deleteReserve_, [&] {
    Stmt s(db_, "DELETE FROM pdms WHERE id = ?1");
    s.bind(1, id).run();
    return sqlite3_changes(db_) > 0;
  });
}

// ---- missions ---------------------------------------------------------------------------------

void Database::insertMission(const MissionRecord& m) {
  const std::string spec = dumpJson(m.spec, "mission spec");
  const std::string metrics = m.metrics.is_null() ? std::string() : dumpJson(m.metrics, "metrics");
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_,
         "INSERT INTO missions(id, map_id, pdm_id, planner, spec, status, message, created_at, "
         "started_at, finished_at, metrics, label) "
         "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)");
  s.bind(1, m.id).bind(2, m.mapId).bind(3, m.pdmId).bind(4, m.planner).bind(5, spec);
  s.bind(6, std::string(enumName(m.status))).bind(7, m.message).bind(8, m.createdAt);
  s.bindOrNull(9, m.startedAt).bindOrNull(10, m.finishedAt).bindOrNull(11, metrics);
  s.bind(12, m.label);
  s.run();
}

std::optional<MissionRecord> Database::getMission(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, (std::string(kMissionSelect) + "WHERE m.id = ?1").c_str());
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return readMission(s);
}

std::vector<MissionRecord> Database::listMissions(long long limit, long long offset) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, (std::string(kMissionSelect) +
               "ORDER BY m.created_at DESC, m.id ASC LIMIT ?1 OFFSET ?2")
                  .c_str());
  s.bindInt(1, limit).bindInt(2, offset);
  std::vector<MissionRecord> out;
  while (s.step()) out.push_back(readMission(s));
  return out;
}

long long Database::countMissions() {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT COUNT(*) FROM missions");
  return s.step() ? s.integer(0) : 0;
}

void Database::updateMission(const std::string& id, RunStatus status,
                             const std::string& message, const nlohmann::json& metrics) {
  const std::string metricsText = metrics.is_null() ? std::string() : dumpJson(metrics, "metrics");
  const std::string now = nowIso();
  std::lock_guard lock(mutex_);
  // A final status may use the reserve: a mission that ran must not stay "running" on a full disk.
  auto update = [&] {
    // In SET expressions `status` is the value before the update, so the timestamps are set only on
    // the transition into running / into a final status (a repeated update keeps the first time).
    static const std::string sql = "UPDATE missions SET "
                                   "  started_at = CASE WHEN ?2 = " + sqlName(RunStatus::Running) +
                                   " AND status <> " + sqlName(RunStatus::Running) + " THEN ?4 "
                                   "                    ELSE started_at END, "
                                   "  finished_at = CASE WHEN ?5 = 1 AND status NOT IN (" + finalStatusList() +
                                   ") THEN ?4 ELSE finished_at END, "
                                   "  metrics = COALESCE(?6, metrics), "
                                   "  status = ?2, message = ?3 "
                                   "WHERE id = ?1";
    Stmt s(db_, sql.c_str());
    s.bind(1, id).bind(2, std::string(enumName(status))).bind(3, message).bind(4, now);
    s.bindInt(5, isFinal(status) ? 1 : 0);
    s.bindOrNull(6, metricsText);
    s.run();
    return sqlite3_changes(db_);
  };
  ensureReserves();
  const int changed = isFinal(status) ? withReserve(statusReserve_, update) : update();
  if (changed == 0) throw std::runtime_error("database: no mission '" + id + "'");
}

bool Database::setMissionLabel(const std::string& id, const std::string& label) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_, "UPDATE missions SET label = ?2 WHERE id = ?1");
  s.bind(1, id).bind(2, label).run();
  return sqlite3_changes(db_) > 0;
}

bool Database::deleteMission(const std::string& id) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  return withReserve(deleteReserve_, [&] {
    Stmt s(db_, "DELETE FROM missions WHERE id = ?1");
    s.bind(1, id).run();
    return sqlite3_changes(db_) > 0;
  });
}

int Database::markUnfinishedInterrupted() {
  const std::string now = nowIso();
  std::lock_guard lock(mutex_);
  return withReserve(statusReserve_, [&] {
    static const std::string sql = "UPDATE missions SET status = " + sqlName(RunStatus::Interrupted) +
                                   ", message = ?1 || status, finished_at = ?2 WHERE status IN (" +
                                   sqlName(RunStatus::Queued) + ", " + sqlName(RunStatus::Running) + ")";
    Stmt s(db_, sql.c_str());
    s.bind(1, std::string("server restarted while the mission was ")).bind(2, now).run();
    return sqlite3_changes(db_);
  });
}

std::string nowIso() {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const auto ms = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
  const std::time_t t = system_clock::to_time_t(now);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[96];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}

}  // namespace rover::store
