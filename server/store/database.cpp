#include "server/store/database.hpp"

#include <sqlite3.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "server/json/json_edge.hpp"
#include "server/store/data_dir.hpp"
#include "server/store/sqlite_stmt.hpp"

// The rows of the server database: maps, their zones, PDMs and missions (opening it and its
// durability: database_open.cpp; its schema: database_schema.cpp).

namespace rover::store {

namespace {

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

MapRecord readMap(const Stmt& s) {
  return MapRecord{s.text(0), s.text(1), s.text(2), parseJson(s, 3, "map meta"), s.integer(4)};
}

PdmRecord readPdm(const Stmt& s) {
  return PdmRecord{s.text(0), s.text(1), s.text(2), s.text(3), parseJson(s, 4, "PDM meta"), s.integer(5)};
}

constexpr const char* kPdmColumns = "SELECT id, map_id, name, created_at, meta, version FROM pdms ";

// A mission row with the names of its map and PDM (empty once they are deleted).
constexpr const char* kMissionSelect =
    "SELECT m.id, m.map_id, m.pdm_id, m.planner, m.spec, m.status, m.message, m.created_at, "
    "m.started_at, m.finished_at, m.metrics, m.label, COALESCE(maps.name, ''), "
    "COALESCE(pdms.name, ''), m.version FROM missions m LEFT JOIN maps ON maps.id = m.map_id "
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
  m.version = s.integer(14);
  return m;
}

}  // namespace

template <class F>
auto Database::withReserve(Reserve& r, F&& write) -> decltype(write()) {
  try {
    return write();
  } catch (const StorageFull&) {
    if (!release(r)) throw;
    return write();
  }
}

template <class F>
auto Database::transaction(F&& body) -> decltype(body()) {
  exec(db_, "BEGIN IMMEDIATE");
  try {
    if constexpr (std::is_void_v<decltype(body())>) {
      body();
      exec(db_, "COMMIT");
    } else {
      auto out = body();
      exec(db_, "COMMIT");
      return out;
    }
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

void Database::recordHistoryLocked(const std::string& kind, const std::string& objectId, long long version,
                                   const std::string& body, const std::string& by) {
  {
    Stmt s(db_, "INSERT OR REPLACE INTO history(kind, object_id, version, by, at, body) VALUES (?1, ?2, ?3, ?4, ?5, ?6)");
    s.bind(1, kind).bind(2, objectId).bindInt(3, version).bind(4, by).bind(5, nowIso()).bind(6, body).run();
  }
  Stmt trim(db_, "DELETE FROM history WHERE kind = ?1 AND object_id = ?2 AND version <= ?3");
  trim.bind(1, kind).bind(2, objectId).bindInt(3, version - kHistoryPerObject).run();
}

void Database::recordHistory(const std::string& kind, const std::string& objectId, long long version,
                             const nlohmann::json& body, const std::string& by) {
  const std::string text = dumpJson(body, "history");
  std::lock_guard lock(mutex_);
  ensureReserves();
  transaction([&] { recordHistoryLocked(kind, objectId, version, text, by); });
}

std::vector<HistoryEntry> Database::history(const std::string& kind, const std::string& objectId) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT version, by, at FROM history WHERE kind = ?1 AND object_id = ?2 ORDER BY version DESC");
  s.bind(1, kind).bind(2, objectId);
  std::vector<HistoryEntry> out;
  while (s.step()) out.push_back(HistoryEntry{s.integer(0), s.text(1), s.text(2), nullptr});
  return out;
}

std::optional<HistoryEntry> Database::historyVersion(const std::string& kind, const std::string& objectId,
                                                     long long version) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT version, by, at, body FROM history WHERE kind = ?1 AND object_id = ?2 AND version = ?3");
  s.bind(1, kind).bind(2, objectId).bindInt(3, version);
  if (!s.step()) return std::nullopt;
  return HistoryEntry{s.integer(0), s.text(1), s.text(2), parseJson(s, 3, "history")};
}

long long Database::counter(const std::string& name) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT value FROM counters WHERE name = ?1");
  s.bind(1, name);
  return s.step() ? s.integer(0) : 0;
}

void Database::setCounter(const std::string& name, long long value) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_, "INSERT INTO counters(name, value) VALUES (?1, ?2) ON CONFLICT(name) DO UPDATE SET value = excluded.value");
  s.bind(1, name).bindInt(2, value).run();
}

// ---- maps -------------------------------------------------------------------------------------

void Database::insertMap(MapRecord& m) {
  const std::string meta = dumpJson(m.meta, "map meta");
  std::lock_guard lock(mutex_);
  ensureReserves();
  const auto taken = [&](const std::string& name) {
    Stmt q(db_, "SELECT 1 FROM maps WHERE name = ?1 LIMIT 1");
    q.bind(1, name);
    return q.step();
  };
  if (taken(m.name)) {
    // Room for the suffix within the name rule's length, cut at a UTF-8 character boundary.
    std::string base = m.name;
    constexpr std::size_t kRoom = 8;  // " (99999)"
    if (base.size() + kRoom > rover::json::kMaxNameChars) {
      std::size_t cut = rover::json::kMaxNameChars > kRoom ? rover::json::kMaxNameChars - kRoom : 0;
      while (cut > 0 && (static_cast<unsigned char>(base[cut]) & 0xC0) == 0x80) --cut;
      base.resize(cut);
    }
    for (int k = 2;; ++k) {
      std::string candidate = base + " (" + std::to_string(k) + ")";
      if (!taken(candidate)) {
        m.name = std::move(candidate);
        break;
      }
    }
  }
  Stmt s(db_, "INSERT INTO maps(id, name, created_at, meta) VALUES (?1, ?2, ?3, ?4)");
  s.bind(1, m.id).bind(2, m.name).bind(3, m.createdAt).bind(4, meta).run();
}

std::optional<MapRecord> Database::getMap(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id, name, created_at, meta, version FROM maps WHERE id = ?1");
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return readMap(s);
}

std::vector<MapRecord> Database::listMaps(long long limit, long long offset) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id, name, created_at, meta, version FROM maps ORDER BY created_at ASC, id ASC LIMIT ?1 OFFSET ?2");
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

bool Database::setMapStorage(const std::string& id, const nlohmann::json& storage) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  // Read and written under the one connection's lock: nothing changes the row in between.
  nlohmann::json meta;
  {
    Stmt s(db_, "SELECT meta FROM maps WHERE id = ?1");
    s.bind(1, id);
    if (!s.step()) return false;
    meta = parseJson(s, 0, "meta");
  }
  meta["storage"] = storage;
  Stmt s(db_, "UPDATE maps SET meta = ?2 WHERE id = ?1");
  s.bind(1, id).bind(2, dumpJson(meta, "meta")).run();
  return sqlite3_changes(db_) > 0;
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

MapRename Database::renameMap(const std::string& id, const std::string& name, long long expected) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  MapRename out;
  {
    Stmt v(db_, "SELECT version FROM maps WHERE id = ?1");
    v.bind(1, id);
    if (!v.step()) return out;  // Missing
    if (v.integer(0) != expected) {
      out.cas = Cas::Stale;
      return out;
    }
  }
  {
    Stmt t(db_, "SELECT id FROM maps WHERE name = ?1 AND id <> ?2 LIMIT 1");
    t.bind(1, name).bind(2, id);
    if (t.step()) {
      out.cas = Cas::Done;
      out.takenBy = t.text(0);
      return out;
    }
  }
  // One connection behind mutex_: nothing else writes between the checks and this update.
  Stmt s(db_, "UPDATE maps SET name = ?2, version = version + 1 WHERE id = ?1 AND version = ?3");
  s.bind(1, id).bind(2, name).bindInt(3, expected).run();
  out.cas = sqlite3_changes(db_) > 0 ? Cas::Done : Cas::Stale;
  return out;
}

bool Database::setZones(const std::string& mapId, const nlohmann::json& zones) {
  const std::string body = dumpJson(zones, "zones");
  std::lock_guard lock(mutex_);
  ensureReserves();
  // One statement: the row is written only while the map exists (a delete racing it wins).
  Stmt s(db_,
         "INSERT INTO zones(map_id, body, updated_at) SELECT ?1, ?2, ?3 WHERE EXISTS "
         "(SELECT 1 FROM maps WHERE id = ?1) ON CONFLICT(map_id) DO UPDATE SET "
         "body = excluded.body, updated_at = excluded.updated_at, version = zones.version + 1");
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

std::optional<ZoneSet> Database::getZoneSet(const std::string& mapId) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT body, version, next_zone FROM zones WHERE map_id = ?1");
  s.bind(1, mapId);
  if (!s.step()) return std::nullopt;
  return ZoneSet{parseJson(s, 0, "zones"), s.integer(1), s.integer(2)};
}

Cas Database::putZoneSet(const std::string& mapId, const ZoneSet& set, long long expected, const std::string& by) {
  const std::string body = dumpJson(set.body, "zones");
  std::lock_guard lock(mutex_);
  ensureReserves();
  return transaction([&] {
    {
      Stmt m(db_, "SELECT 1 FROM maps WHERE id = ?1");
      m.bind(1, mapId);
      if (!m.step()) return Cas::Missing;
    }
    long long stored = 0;
    {
      Stmt v(db_, "SELECT version FROM zones WHERE map_id = ?1");
      v.bind(1, mapId);
      if (v.step()) stored = v.integer(0);
    }
    if (stored != expected) return Cas::Stale;
    Stmt w(db_,
           "INSERT INTO zones(map_id, body, updated_at, version, next_zone) VALUES (?1, ?2, ?3, ?4, ?5) "
           "ON CONFLICT(map_id) DO UPDATE SET body = excluded.body, updated_at = excluded.updated_at, "
           "version = excluded.version, next_zone = excluded.next_zone");
    w.bind(1, mapId).bind(2, body).bind(3, nowIso()).bindInt(4, expected + 1).bindInt(5, set.nextZone).run();
    recordHistoryLocked("zones", mapId, expected + 1, body, by);
    return Cas::Done;
  });
}

// ---- PDMs -------------------------------------------------------------------------------------

void Database::insertPdm(const PdmRecord& p, const std::string& by) {
  const std::string meta = dumpJson(p.meta, "PDM meta");
  const std::string first = dumpJson(nlohmann::json{{"name", p.name}, {"meta", p.meta}}, "history");
  std::lock_guard lock(mutex_);
  ensureReserves();
  transaction([&] {
    Stmt s(db_, "INSERT INTO pdms(id, map_id, name, created_at, meta, version) VALUES (?1, ?2, ?3, ?4, ?5, 1)");
    s.bind(1, p.id).bind(2, p.mapId).bind(3, p.name).bind(4, p.createdAt).bind(5, meta).run();
    recordHistoryLocked("pdm", p.id, 1, first, by);
  });
}

std::optional<PdmRecord> Database::getPdm(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(db_, (std::string(kPdmColumns) + "WHERE id = ?1").c_str());
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return readPdm(s);
}

std::vector<PdmRecord> Database::listPdms(const std::string& mapId, long long limit, long long offset) {
  std::lock_guard lock(mutex_);
  Stmt s(db_,
         (std::string(kPdmColumns) + "WHERE map_id = ?1 "
         "ORDER BY created_at ASC, id ASC LIMIT ?2 OFFSET ?3").c_str());
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

Cas Database::updatePdm(const PdmRecord& p, long long expected, const nlohmann::json& body, const std::string& by,
                       const std::function<void()>& before) {
  const std::string meta = dumpJson(p.meta, "PDM meta"), text = dumpJson(body, "history");
  std::lock_guard lock(mutex_);
  ensureReserves();
  return transaction([&] {
    {
      Stmt v(db_, "SELECT version FROM pdms WHERE id = ?1");
      v.bind(1, p.id);
      if (!v.step()) return Cas::Missing;
      if (v.integer(0) != expected) return Cas::Stale;
    }
    if (before) before();
    Stmt w(db_, "UPDATE pdms SET name = ?2, meta = ?3, version = ?4 WHERE id = ?1");
    w.bind(1, p.id).bind(2, p.name).bind(3, meta).bindInt(4, expected + 1).run();
    recordHistoryLocked("pdm", p.id, expected + 1, text, by);
    return Cas::Done;
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
  Stmt s(db_, "UPDATE missions SET label = ?2, version = version + 1 WHERE id = ?1");
  s.bind(1, id).bind(2, label).run();
  return sqlite3_changes(db_) > 0;
}

Cas Database::relabelMission(const std::string& id, const std::string& label, long long expected) {
  std::lock_guard lock(mutex_);
  ensureReserves();
  Stmt s(db_, "UPDATE missions SET label = ?2, version = version + 1 WHERE id = ?1 AND version = ?3");
  s.bind(1, id).bind(2, label).bindInt(3, expected).run();
  if (sqlite3_changes(db_) > 0) return Cas::Done;
  Stmt e(db_, "SELECT 1 FROM missions WHERE id = ?1");
  e.bind(1, id);
  return e.step() ? Cas::Stale : Cas::Missing;
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
