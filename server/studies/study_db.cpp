#include "server/studies/study_db.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <ostream>
#include <sstream>

#include "server/json/plan_json.hpp"
#include "server/store/sqlite_stmt.hpp"
#include "server/studies/study_summary.hpp"
#include "server/studies/study_version.hpp"

namespace rover::studies {

using store::exec;
using store::Stmt;

namespace {

constexpr int kSchemaVersion = 1;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS study(
  id         INTEGER PRIMARY KEY CHECK (id = 1),
  name       TEXT NOT NULL,
  spec       TEXT NOT NULL,
  version    TEXT NOT NULL,
  created_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS configs(
  config_id INTEGER PRIMARY KEY,
  name      TEXT NOT NULL,
  planner   TEXT NOT NULL,
  world     TEXT NOT NULL,
  rovers    INTEGER NOT NULL,
  params    TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs(
  run_index INTEGER PRIMARY KEY,
  config_id INTEGER NOT NULL,
  replicate INTEGER NOT NULL,
  seed      INTEGER NOT NULL,
  status    TEXT NOT NULL,
  wall_s    REAL,
  cpu_s     REAL,
  host      TEXT,
  rank      INTEGER,
  version   TEXT
);
CREATE INDEX IF NOT EXISTS runs_config ON runs(config_id);
CREATE TABLE IF NOT EXISTS metrics(
  key TEXT PRIMARY KEY,
  ord INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS curves(
  run_index INTEGER NOT NULL,
  curve     TEXT NOT NULL,
  x         TEXT NOT NULL,
  y         TEXT NOT NULL,
  PRIMARY KEY (run_index, curve)
) WITHOUT ROWID;
)sql";

// The fixed columns of runs; a metric of the same name gets the column "metric_<key>".
const std::vector<std::string>& fixedColumns() {
  static const std::vector<std::string> c{"run_index", "config_id", "replicate", "seed", "status",
                                          "wall_s",    "cpu_s",     "host",      "rank", "version"};
  return c;
}

std::string columnOf(const std::string& key) {
  for (const auto& c : fixedColumns())
    if (c == key) return "metric_" + key;
  return key;
}

std::string quoted(const std::string& id) {
  std::string out = "\"";
  for (char c : id) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// Exact and locale-free: %.17g round-trips every double.
std::string exact(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string jsonArray(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0) out += ',';
    out += exact(v[i]);
  }
  return out + "]";
}

std::string nowIso() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// A new study database is made whole beside `path` (WAL mode, schema) and linked into place, so
// no other connection ever opens it half made. A study's first reads (the page's GET of the
// study and its runs.csv, right after the launch) used to open the file the executor had just
// created: two connections switching a new file to WAL at once get "database is locked" at
// once, whatever the busy timeout, and either the study failed ("internal error") or the read
// answered 500 (Python's sqlite3, two processes racing on a new file: 6 failures in 1200
// openings; none in 1200 once the file appears whole). link() refuses an existing path: of two
// openers making the same database, one wins and both open the winner's.
void createWhole(const std::string& path) {
  namespace fs = std::filesystem;
  // An in-memory database (a sweep without --out) or a URI is SQLite's to make.
  if (path.empty() || path == ":memory:" || path.rfind("file:", 0) == 0) return;
  std::error_code ec;
  if (fs::exists(path, ec)) return;
  static std::atomic<unsigned> counter{0};
  const std::string temp = path + ".new." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  const auto removeTemp = [&temp] {
    std::error_code ignored;
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(temp + suffix, ignored);
  };
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(temp.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    removeTemp();
    throw std::runtime_error("cannot create the study database " + path + ": " + msg);
  }
  try {
    // One transaction, no sync until the close's checkpoint: nobody sees this file before the link.
    exec(db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;");
    exec(db, (std::string("BEGIN;") + kSchema + "PRAGMA user_version=" + std::to_string(kSchemaVersion) + "; COMMIT;").c_str());
  } catch (...) {
    sqlite3_close(db);
    removeTemp();
    throw;
  }
  sqlite3_close(db);  // the last connection: its WAL is checkpointed and removed
  const int linked = ::link(temp.c_str(), path.c_str());
  const int err = errno;
  removeTemp();
  if (linked != 0 && err != EEXIST)
    throw std::runtime_error("cannot create the study database " + path + ": " + std::strerror(err));
}

}  // namespace

nlohmann::json toJson(const StudySummary& s) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : s.rows) {
    const Summary& m = r.summary;
    rows.push_back({{"config", r.config}, {"metric", r.metric}, {"runs", r.runs}, {"n", m.count},
                    {"mean", num(m.mean)}, {"std", num(m.stddev)}, {"p5", num(m.p5)}, {"p50", num(m.p50)},
                    {"p95", num(m.p95)}, {"min", num(m.min)}, {"max", num(m.max)}});
  }
  return {{"study", s.name}, {"runs_done", s.runsDone}, {"runs_total", s.runsTotal},
          {"run_wall_s", s.wallSeconds}, {"rows", rows}};
}

StudyDb StudyDb::open(const std::string& path) {
  createWhole(path);
  sqlite3* db = nullptr;
  // Created above, or by SQLite when in memory.
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw std::runtime_error("cannot open the study database " + path + ": " + msg);
  }
  StudyDb out(db);
  sqlite3_busy_timeout(db, 10000);
  exec(db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;");
  long long version = 0;
  {
    Stmt v(db, "PRAGMA user_version");
    v.step();
    version = v.integer(0);
  }
  if (version > kSchemaVersion)
    throw std::runtime_error(path + " was written by a newer roverplan (study schema " + std::to_string(version) + ")");
  if (version < kSchemaVersion) {  // an empty file (createWhole makes ours whole): made a study database
    exec(db, kSchema);
    exec(db, ("PRAGMA user_version=" + std::to_string(kSchemaVersion)).c_str());
  }
  Stmt cols(db, "SELECT key FROM metrics");
  while (cols.step()) out.columns_.insert(cols.text(0));
  return out;
}

StudyDb::StudyDb(sqlite3* db) : db_(db) {}
StudyDb::StudyDb(StudyDb&& other) noexcept : db_(other.db_), columns_(std::move(other.columns_)) {
  other.db_ = nullptr;
}
StudyDb::~StudyDb() {
  if (db_) sqlite3_close(db_);
}

bool StudyDb::hasSpec() const {
  Stmt s(db_, "SELECT count(*) FROM study");
  s.step();
  return s.integer(0) > 0;
}

nlohmann::json StudyDb::specJson() const {
  Stmt s(db_, "SELECT spec FROM study WHERE id = 1");
  if (!s.step()) throw Error(ErrorCode::InvalidInput, "study", "the database holds no study");
  return nlohmann::json::parse(s.text(0));
}

void StudyDb::attach(const StudySpec& spec) {
  const std::string text = spec.json.dump();
  if (hasSpec()) {
    if (specJson().dump() != text)
      throw Error(ErrorCode::InvalidInput, "spec",
                  "the database holds a different study (another spec, preset or --runs); use a new --out");
    return;
  }
  exec(db_, "BEGIN IMMEDIATE");
  try {
    Stmt st(db_, "INSERT INTO study(id, name, spec, version, created_at) VALUES (1, ?, ?, ?, ?)");
    st.bind(1, spec.name).bind(2, text).bind(3, kStudyVersion).bind(4, nowIso()).run();
    Stmt c(db_, "INSERT INTO configs(config_id, name, planner, world, rovers, params) VALUES (?, ?, ?, ?, ?, ?)");
    for (const auto& cfg : spec.configurations) {
      nlohmann::json params = nlohmann::json::object();
      for (const auto& [k, v] : cfg.point.params) params[k] = json::toJson(v);
      c.bindInt(1, cfg.id).bind(2, cfg.name).bind(3, cfg.point.planner).bind(4, spec.worlds[cfg.world].name);
      c.bindInt(5, cfg.rovers).bind(6, params.dump()).run();
      c.reset();
    }
    exec(db_, "COMMIT");
  } catch (...) {
    exec(db_, "ROLLBACK");
    throw;
  }
}

std::vector<std::int64_t> StudyDb::doneRuns() const {
  std::vector<std::int64_t> out;
  Stmt s(db_, "SELECT run_index FROM runs ORDER BY run_index");
  while (s.step()) out.push_back(s.integer(0));
  return out;
}

std::size_t StudyDb::runCount() const {
  Stmt s(db_, "SELECT count(*) FROM runs");
  s.step();
  return static_cast<std::size_t>(s.integer(0));
}

void StudyDb::ensureMetricColumns(const std::vector<RunRow>& rows) {
  for (const auto& r : rows) {
    for (std::size_t i = 0; i < r.metrics.size(); ++i) {
      const std::string& key = r.metrics[i].first;
      if (columns_.count(key)) continue;
      exec(db_, ("ALTER TABLE runs ADD COLUMN " + quoted(columnOf(key)) + " REAL").c_str());
      Stmt m(db_, "INSERT INTO metrics(key, ord) VALUES (?, (SELECT count(*) FROM metrics))");
      m.bind(1, key).run();
      columns_.insert(key);
    }
  }
}

void StudyDb::insert(const std::vector<RunRow>& rows) {
  if (rows.empty()) return;
  exec(db_, "BEGIN IMMEDIATE");
  try {
    ensureMetricColumns(rows);
    // One prepared insert per metric set (a planner's rows share one).
    std::map<std::string, std::unique_ptr<Stmt>> inserts;
    Stmt curve(db_, "INSERT OR IGNORE INTO curves(run_index, curve, x, y) VALUES (?, ?, ?, ?)");
    for (const auto& r : rows) {
      std::string cols = "run_index, config_id, replicate, seed, status, wall_s, cpu_s, host, rank, version";
      std::string marks = "?, ?, ?, ?, ?, ?, ?, ?, ?, ?";
      for (const auto& [key, value] : r.metrics) {
        cols += ", " + quoted(columnOf(key));
        marks += ", ?";
      }
      const std::string sql = "INSERT OR IGNORE INTO runs(" + cols + ") VALUES (" + marks + ")";
      auto& st = inserts[sql];
      if (!st) st = std::make_unique<Stmt>(db_, sql.c_str());
      st->bindInt(1, r.runIndex).bindInt(2, r.configId).bindInt(3, r.replicate);
      st->bindInt(4, static_cast<long long>(r.seed)).bind(5, r.status).bindReal(6, r.wallSeconds);
      st->bindReal(7, r.cpuSeconds).bind(8, r.host).bindInt(9, r.rank).bind(10, kStudyVersion);
      int i = 11;
      for (const auto& [key, value] : r.metrics) st->bindReal(i++, value);
      st->run();
      st->reset();
      for (const auto& c : r.curves) {
        curve.bindInt(1, r.runIndex).bind(2, c.key).bind(3, jsonArray(c.x)).bind(4, jsonArray(c.y)).run();
        curve.reset();
      }
    }
    exec(db_, "COMMIT");
  } catch (...) {
    exec(db_, "ROLLBACK");
    throw;
  }
}

std::vector<std::string> StudyDb::metricKeys() const {
  std::vector<std::string> out;
  Stmt s(db_, "SELECT key FROM metrics ORDER BY ord, key");
  while (s.step()) out.push_back(s.text(0));
  return out;
}

std::string StudyDb::metricColumnSql(const std::string& key) { return quoted(columnOf(key)); }

void StudyDb::mergeFrom(const std::string& path) {
  {
    Stmt a(db_, "ATTACH DATABASE ? AS src");
    a.bind(1, path).run();
  }
  try {
    std::string srcSpec;
    {
      Stmt s(db_, "SELECT spec FROM src.study WHERE id = 1");
      if (!s.step()) throw Error(ErrorCode::InvalidInput, "in", path + " holds no study");
      srcSpec = s.text(0);
    }
    exec(db_, "BEGIN IMMEDIATE");
    try {
      if (!hasSpec()) {
        exec(db_, "INSERT INTO study SELECT * FROM src.study");
        exec(db_, "INSERT INTO configs SELECT * FROM src.configs");
      } else if (nlohmann::json::parse(srcSpec).dump() != specJson().dump()) {
        throw Error(ErrorCode::InvalidInput, "in", path + " holds a different study (its spec differs)");
      }
      std::vector<std::string> keys;
      {
        Stmt k(db_, "SELECT key FROM src.metrics ORDER BY ord, key");
        while (k.step()) keys.push_back(k.text(0));
      }
      RunRow probe;
      for (const auto& k : keys) probe.metrics.push_back({k, 0});
      ensureMetricColumns({probe});
      std::string cols = "run_index, config_id, replicate, seed, status, wall_s, cpu_s, host, rank, version";
      for (const auto& k : keys) cols += ", " + quoted(columnOf(k));
      exec(db_, ("INSERT OR IGNORE INTO runs(" + cols + ") SELECT " + cols + " FROM src.runs").c_str());
      exec(db_, "INSERT OR IGNORE INTO curves SELECT * FROM src.curves");
      exec(db_, "COMMIT");
    } catch (...) {
      exec(db_, "ROLLBACK");
      throw;
    }
  } catch (...) {
    exec(db_, "DETACH DATABASE src");
    throw;
  }
  exec(db_, "DETACH DATABASE src");
}

void StudyDb::accumulate(SummaryAccumulator& acc) const {
  // The metrics in the table's order first, so the rows come in the order the runs reported them.
  const std::vector<std::string> keys = metricKeys();
  std::vector<std::size_t> index;
  for (const auto& k : keys) index.push_back(acc.metricIndex(k));
  std::string cols = "run_index, config_id, wall_s, cpu_s";
  for (const auto& k : keys) cols += ", " + quoted(columnOf(k));
  Stmt s(db_, ("SELECT " + cols + " FROM runs").c_str());
  std::vector<std::pair<std::size_t, double>> values;
  while (s.step()) {
    values.clear();
    for (std::size_t k = 0; k < keys.size(); ++k)
      if (!s.isNull(static_cast<int>(k) + 4)) values.emplace_back(index[k], s.real(static_cast<int>(k) + 4));
    acc.add(s.integer(0), static_cast<int>(s.integer(1)), s.real(2), s.real(3), values);
  }
}

StudySummary StudyDb::summary(bool timing) const {
  SummaryAccumulator acc(parseStudySpec(specJson()));
  accumulate(acc);
  return acc.summary(timing);
}

std::string StudyDb::runsCsv() const {
  std::ostringstream out;
  runsCsv(out);
  return out.str();
}

void StudyDb::runsCsv(std::ostream& out) const {
  const std::vector<std::string> keys = metricKeys();
  out << "run_index,config_id,config,replicate,seed,status,wall_s,cpu_s,host,rank,version";
  std::string cols = "r.run_index, r.config_id, c.name, r.replicate, r.seed, r.status, r.wall_s, r.cpu_s, r.host, r.rank, r.version";
  for (const auto& k : keys) {
    out << "," << k;
    cols += ", r." + quoted(columnOf(k));
  }
  out << "\n";
  Stmt s(db_, ("SELECT " + cols + " FROM runs r JOIN configs c USING (config_id) ORDER BY r.run_index").c_str());
  auto csvText = [](std::string t) {
    if (t.find_first_of(",\"\n") == std::string::npos) return t;
    std::string q = "\"";
    for (char ch : t) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return q + "\"";
  };
  while (s.step()) {
    out << s.integer(0) << "," << s.integer(1) << "," << csvText(s.text(2)) << "," << s.integer(3) << ","
        << s.integer(4) << "," << csvText(s.text(5)) << "," << exact(s.real(6)) << "," << exact(s.real(7)) << ","
        << csvText(s.text(8)) << "," << s.integer(9) << "," << csvText(s.text(10));
    for (std::size_t k = 0; k < keys.size(); ++k) {
      out << ",";
      if (!s.isNull(static_cast<int>(k) + 11)) out << exact(s.real(static_cast<int>(k) + 11));
    }
    out << "\n";
  }
}

void StudyDb::dump(std::ostream& out) const {
  std::vector<std::string> keys = metricKeys();
  std::sort(keys.begin(), keys.end());
  out << "spec " << specJson().dump() << "\n";
  std::string cols = "run_index, config_id, replicate, seed, status";
  for (const auto& k : keys) cols += ", " + quoted(columnOf(k));
  Stmt s(db_, ("SELECT " + cols + " FROM runs ORDER BY run_index").c_str());
  while (s.step()) {
    out << "run " << s.integer(0) << " config " << s.integer(1) << " replicate " << s.integer(2) << " seed "
        << s.integer(3) << " status " << s.text(4);
    for (std::size_t k = 0; k < keys.size(); ++k) {
      const int col = static_cast<int>(k) + 5;
      out << " " << keys[k] << "=" << (s.isNull(col) ? std::string("null") : exact(s.real(col)));
    }
    out << "\n";
  }
  Stmt c(db_, "SELECT run_index, curve, x, y FROM curves ORDER BY run_index, curve");
  while (c.step()) out << "curve " << c.integer(0) << " " << c.text(1) << " " << c.text(2) << " " << c.text(3) << "\n";
}

}  // namespace rover::studies
