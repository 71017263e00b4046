#include "server/store/database_schema.hpp"

#include <stdexcept>

#include "server/store/sqlite_stmt.hpp"

namespace rover::store {

namespace {

constexpr int kSchemaVersion = 5;

// Version 1 of the schema. Later versions add a migrate step from N-1 below.
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

// Version 4 (issue 26, several operators): a version on every mutable row (a write names the
// version it read: a stale one is refused, never applied), the zones' own ids, the saved versions
// of PDMs and zone sets (history, at most kHistoryPerObject per object, trimmed on write; gone
// with their object through the triggers), and the event stream's last sequence number.
constexpr const char* kMigrateV3toV4 = R"sql(
ALTER TABLE pdms ADD COLUMN version INTEGER NOT NULL DEFAULT 1;
ALTER TABLE missions ADD COLUMN version INTEGER NOT NULL DEFAULT 1;
ALTER TABLE zones ADD COLUMN version INTEGER NOT NULL DEFAULT 1;
ALTER TABLE zones ADD COLUMN next_zone INTEGER NOT NULL DEFAULT 1;
CREATE TABLE IF NOT EXISTS history(
  kind      TEXT NOT NULL,
  object_id TEXT NOT NULL,
  version   INTEGER NOT NULL,
  by        TEXT NOT NULL DEFAULT '',
  at        TEXT NOT NULL,
  body      TEXT NOT NULL,
  PRIMARY KEY(kind, object_id, version)
);
CREATE TRIGGER IF NOT EXISTS pdm_history_gone AFTER DELETE ON pdms BEGIN
  DELETE FROM history WHERE kind = 'pdm' AND object_id = old.id;
END;
CREATE TRIGGER IF NOT EXISTS zones_history_gone AFTER DELETE ON maps BEGIN
  DELETE FROM history WHERE kind = 'zones' AND object_id = old.id;
END;
CREATE TABLE IF NOT EXISTS counters(
  name  TEXT PRIMARY KEY,
  value INTEGER NOT NULL
);
)sql";

// Version 5 (issue 26): a map's name is editable, so maps carry a version like every other
// mutable row; a map stored before counts as version 1.
constexpr const char* kMigrateV4toV5 = R"sql(
ALTER TABLE maps ADD COLUMN version INTEGER NOT NULL DEFAULT 1;
)sql";

}  // namespace

void migrateSchema(sqlite3* db, const std::string& path) {
  exec(db, "BEGIN IMMEDIATE");
  try {
    exec(db, "CREATE TABLE IF NOT EXISTS schema_version(version INTEGER NOT NULL)");
    long long version = 0;
    {
      Stmt s(db, "SELECT MAX(version) FROM schema_version");
      if (s.step() && !s.isNull(0)) version = s.integer(0);
    }
    if (version > kSchemaVersion)
      throw std::runtime_error("database: '" + path + "' has schema version " +
                               std::to_string(version) + ", newer than this server supports (" +
                               std::to_string(kSchemaVersion) + ")");
    // A new file gets version 1, then every migration from N-1 to N in turn.
    exec(db, kSchemaV1);
    if (version == 0) {
      Stmt s(db, "INSERT INTO schema_version(version) VALUES (1)");
      s.run();
      version = 1;
    }
    if (version == 1) {
      exec(db, kMigrateV1toV2);
      Stmt s(db, "INSERT INTO schema_version(version) VALUES (2)");
      s.run();
      version = 2;
    }
    if (version == 2) {
      exec(db, kMigrateV2toV3);
      Stmt s(db, "INSERT INTO schema_version(version) VALUES (3)");
      s.run();
      version = 3;
    }
    if (version == 3) {
      exec(db, kMigrateV3toV4);
      Stmt s(db, "INSERT INTO schema_version(version) VALUES (4)");
      s.run();
      version = 4;
    }
    if (version == 4) {
      exec(db, kMigrateV4toV5);
      Stmt s(db, "INSERT INTO schema_version(version) VALUES (5)");
      s.run();
      version = 5;
    }
    exec(db, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace rover::store
