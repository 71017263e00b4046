#include "server/store/database.hpp"
#include "server/store/data_dir.hpp"
#include "tests/wait_until.hpp"
#include <doctest/doctest.h>

#include <signal.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using rover::store::Database;
using rover::store::DataDir;
using rover::store::MapRecord;
using rover::store::MissionRecord;
using rover::store::PdmRecord;
using rover::store::Cas;
using rover::store::ZoneSet;
using rover::store::kHistoryPerObject;
using rover::RunStatus;
using rover::enumName;
using nlohmann::json;

namespace {

// A unique folder under the system temp directory, removed with everything in it.
struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("rover-store-test-" + DataDir::newId());
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::permissions(path, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string db() const { return (path / "test.db").string(); }
};

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> listNames(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  return out;
}

// Runs one SQL query on a separate raw connection and returns the first column of the first row.
std::string rawQuery(const std::string& dbPath, const char* sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(dbPath.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, sql, -1, &st, nullptr) == SQLITE_OK);
  std::string out;
  if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0) != nullptr)
    out = reinterpret_cast<const char*>(sqlite3_column_text(st, 0));
  sqlite3_finalize(st);
  sqlite3_close(db);
  return out;
}

MapRecord makeMap(const std::string& id, const std::string& createdAt) {
  return MapRecord{id, "map " + id, createdAt,
                   json{{"size", {512, 256}},
                        {"cellSize", 0.5},
                        {"crs", "EPSG:4326"},
                        {"elevation", {{"min", -12.25}, {"max", 830.5}}},
                        {"classes", {{"rock", 0.125}, {"sand", 0.875}}},
                        {"files", json::array({"dem.tif", "slope.bin"})},
                        {"note", "ünïcødé \"quoted\" 'single'; DROP TABLE maps; --"}}};
}

MissionRecord makeMission(const std::string& id, const std::string& mapId,
                          const std::string& createdAt, RunStatus status = RunStatus::Queued) {
  MissionRecord m;
  m.id = id;
  m.mapId = mapId;
  m.pdmId = "";
  m.planner = "coverage";
  m.spec = json{{"rovers", json::array({{{"x", 1}, {"y", 2}}})}, {"params", {{"budget", 1e6}}}};
  m.status = status;
  m.createdAt = createdAt;
  return m;
}

// prefix + number (built with append: GCC 12 -O3 warns falsely on "x" + std::to_string(i)).
std::string numbered(std::string prefix, int i) {
  prefix += std::to_string(i);
  return prefix;
}

const std::regex kIsoRe(R"(^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{3}Z$)");

}  // namespace

// ---- Database ---------------------------------------------------------------------------------

TEST_CASE("database: a map's name is unique in the catalog: a taken one gets \" (k)\"") {
  TempDir t;
  Database db(t.db());
  std::vector<std::string> names;
  for (const char* id : {"p1", "p2", "p3"}) {
    MapRecord m = makeMap(id, "2026-01-01T00:00:00.000Z");
    m.name = "megt90n000cb.lbl";
    db.insertMap(m);
    names.push_back(m.name);
    CHECK(db.getMap(id)->name == m.name);
  }
  CHECK(names == std::vector<std::string>{"megt90n000cb.lbl", "megt90n000cb.lbl (2)", "megt90n000cb.lbl (3)"});
  // A name at the length limit keeps within it (200 characters) with its suffix.
  MapRecord a = makeMap("l1", "2026-01-01T00:00:00.000Z"), b = makeMap("l2", "2026-01-01T00:00:00.000Z");
  a.name = b.name = std::string(200, 'x');
  db.insertMap(a);
  db.insertMap(b);
  CHECK(b.name == std::string(192, 'x') + " (2)");
}

TEST_CASE("database: maps round trip with JSON meta") {
  TempDir t;
  Database db(t.db());
  const MapRecord a = makeMap("a1", "2026-01-02T00:00:00.000Z");
  const MapRecord b = makeMap("b2", "2026-01-01T00:00:00.000Z");
  db.insertMap(a);
  db.insertMap(b);

  auto got = db.getMap("a1");
  REQUIRE(got.has_value());
  CHECK(got->id == "a1");
  CHECK(got->name == "map a1");
  CHECK(got->createdAt == a.createdAt);
  CHECK(got->meta == a.meta);
  CHECK_FALSE(db.getMap("nope").has_value());

  const auto all = db.listMaps();  // oldest first
  REQUIRE(all.size() == 2);
  CHECK(all[0].id == "b2");
  CHECK(all[1].id == "a1");

  CHECK_THROWS_AS(db.insertMap(a), std::runtime_error);  // duplicate id
  CHECK(db.deleteMap("a1"));
  CHECK_FALSE(db.deleteMap("a1"));
  CHECK_FALSE(db.getMap("a1").has_value());
  CHECK(db.listMaps().size() == 1);
}

TEST_CASE("database: values are bound, never spliced into SQL") {
  TempDir t;
  Database db(t.db());
  MapRecord m = makeMap("x'); DROP TABLE maps; --", "2026-01-01T00:00:00.000Z");
  m.name = "Robert'); DROP TABLE missions;-- \"";
  db.insertMap(m);
  auto got = db.getMap(m.id);
  REQUIRE(got.has_value());
  CHECK(got->name == m.name);
  CHECK(db.listMaps().size() == 1);
}

TEST_CASE("database: PDMs round trip, need an existing map") {
  TempDir t;
  Database db(t.db());
  db.insertMap(makeMap("m1", "2026-01-01T00:00:00.000Z"));
  db.insertMap(makeMap("m2", "2026-01-01T00:00:00.000Z"));
  const PdmRecord p1{"p1", "m1", "gauss", "2026-01-01T00:00:01.000Z",
                     json{{"kind", "gaussians"},
                          {"components", json::array({{{"x", 1.5}, {"y", 2.5}, {"sigma", 3}}})}}};
  const PdmRecord p2{"p2", "m1", "rand", "2026-01-01T00:00:00.500Z", json{{"kind", "random"}}};
  const PdmRecord p3{"p3", "m2", "raster", "2026-01-01T00:00:00.000Z", json{{"kind", "raster"}}};
  db.insertPdm(p1);
  db.insertPdm(p2);
  db.insertPdm(p3);

  auto got = db.getPdm("p1");
  REQUIRE(got.has_value());
  CHECK(got->mapId == "m1");
  CHECK(got->name == "gauss");
  CHECK(got->createdAt == p1.createdAt);
  CHECK(got->meta == p1.meta);

  const auto ofM1 = db.listPdms("m1");
  REQUIRE(ofM1.size() == 2);
  CHECK(ofM1[0].id == "p2");
  CHECK(ofM1[1].id == "p1");
  CHECK(db.listPdms("none").empty());

  // Foreign key: a PDM of an unknown map is refused.
  CHECK_THROWS_AS(db.insertPdm(PdmRecord{"p4", "ghost", "x", "t", json::object()}),
                  std::runtime_error);

  CHECK(db.deletePdm("p2"));
  CHECK_FALSE(db.deletePdm("p2"));
  CHECK(db.listPdms("m1").size() == 1);
}

TEST_CASE("database: missions round trip, newest first") {
  TempDir t;
  Database db(t.db());
  MissionRecord a = makeMission("ma", "m1", "2026-01-01T00:00:00.000Z");
  MissionRecord b = makeMission("mb", "m1", "2026-01-03T00:00:00.000Z", RunStatus::Succeeded);
  b.pdmId = "p9";
  b.message = "done";
  b.startedAt = "2026-01-03T00:00:01.000Z";
  b.finishedAt = "2026-01-03T00:00:02.000Z";
  b.metrics = json{{"coverage", 0.93}, {"energy", 1234.5}, {"steps", 77}};
  MissionRecord c = makeMission("mc", "m2", "2026-01-02T00:00:00.000Z");
  db.insertMission(a);
  db.insertMission(b);
  db.insertMission(c);

  auto gotA = db.getMission("ma");
  REQUIRE(gotA.has_value());
  CHECK(gotA->mapId == "m1");
  CHECK(gotA->pdmId.empty());
  CHECK(gotA->planner == "coverage");
  CHECK(gotA->spec == a.spec);
  CHECK(gotA->status == RunStatus::Queued);
  CHECK(gotA->message.empty());
  CHECK(gotA->createdAt == a.createdAt);
  CHECK(gotA->startedAt.empty());
  CHECK(gotA->finishedAt.empty());
  CHECK(gotA->metrics.is_null());

  auto gotB = db.getMission("mb");
  REQUIRE(gotB.has_value());
  CHECK(gotB->pdmId == "p9");
  CHECK(gotB->status == RunStatus::Succeeded);
  CHECK(gotB->message == "done");
  CHECK(gotB->startedAt == b.startedAt);
  CHECK(gotB->finishedAt == b.finishedAt);
  CHECK(gotB->metrics == b.metrics);

  CHECK_FALSE(db.getMission("zz").has_value());
  CHECK_THROWS_AS(db.insertMission(a), std::runtime_error);

  const auto all = db.listMissions();
  REQUIRE(all.size() == 3);
  CHECK(all[0].id == "mb");
  CHECK(all[1].id == "mc");
  CHECK(all[2].id == "ma");
}

TEST_CASE("database: deleting a map cascades its PDMs but keeps its missions") {
  TempDir t;
  Database db(t.db());
  db.insertMap(makeMap("m1", "2026-01-01T00:00:00.000Z"));
  db.insertMap(makeMap("m2", "2026-01-01T00:00:00.000Z"));
  db.insertPdm(PdmRecord{"p1", "m1", "a", "2026-01-01T00:00:00.000Z", json::object()});
  db.insertPdm(PdmRecord{"p2", "m1", "b", "2026-01-01T00:00:00.000Z", json::object()});
  db.insertPdm(PdmRecord{"p3", "m2", "c", "2026-01-01T00:00:00.000Z", json::object()});
  MissionRecord mission = makeMission("x1", "m1", "2026-01-01T00:00:00.000Z", RunStatus::Succeeded);
  mission.pdmId = "p1";
  db.insertMission(mission);

  CHECK(db.deleteMap("m1"));
  CHECK_FALSE(db.getPdm("p1").has_value());
  CHECK_FALSE(db.getPdm("p2").has_value());
  CHECK(db.listPdms("m1").empty());
  CHECK(db.getPdm("p3").has_value());  // another map's PDM stays
  auto kept = db.getMission("x1");
  REQUIRE(kept.has_value());
  CHECK(kept->mapId == "m1");
  CHECK(kept->pdmId == "p1");
  CHECK(kept->status == RunStatus::Succeeded);
}

TEST_CASE("database: updateMission sets timestamps and metrics") {
  TempDir t;
  Database db(t.db());
  db.insertMission(makeMission("m", "map", "2026-01-01T00:00:00.000Z"));

  db.updateMission("m", RunStatus::Running, "");
  auto r = db.getMission("m");
  REQUIRE(r.has_value());
  CHECK(r->status == RunStatus::Running);
  CHECK(std::regex_match(r->startedAt, kIsoRe));
  CHECK(r->finishedAt.empty());
  CHECK(r->metrics.is_null());
  const std::string started = r->startedAt;

  // Once the clock reads later than startedAt, a reset of it would show.
  rover::test::waitUntil([&] { return rover::store::nowIso() > started; }, "the clock to pass startedAt");
  db.updateMission("m", RunStatus::Running, "50% done");  // still running: startedAt unchanged
  r = db.getMission("m");
  CHECK(r->message == "50% done");
  CHECK(r->startedAt == started);

  const json metrics{{"coverage", 0.5}, {"paths", json::array({1, 2, 3})}};
  db.updateMission("m", RunStatus::Succeeded, "", metrics);
  r = db.getMission("m");
  CHECK(r->status == RunStatus::Succeeded);
  CHECK(r->message.empty());
  CHECK(r->startedAt == started);
  CHECK(std::regex_match(r->finishedAt, kIsoRe));
  CHECK(r->finishedAt >= r->startedAt);
  CHECK(r->metrics == metrics);

  db.updateMission("m", RunStatus::Succeeded, "note");  // null metrics keep the stored ones
  r = db.getMission("m");
  CHECK(r->metrics == metrics);
  CHECK(r->message == "note");

  for (RunStatus final : {RunStatus::Failed, RunStatus::Cancelled, RunStatus::Interrupted}) {
    const std::string id = "f-" + std::string(enumName(final));
    db.insertMission(makeMission(id, "map", "2026-01-01T00:00:00.000Z"));
    db.updateMission(id, final, "why");
    r = db.getMission(id);
    CHECK(r->status == final);
    CHECK(r->message == "why");
    CHECK(r->startedAt.empty());
    CHECK(std::regex_match(r->finishedAt, kIsoRe));
  }

  CHECK_THROWS_AS(db.updateMission("ghost", RunStatus::Running, ""), std::runtime_error);
}

TEST_CASE("database: markUnfinishedInterrupted after a restart") {
  TempDir t;
  {
    Database db(t.db());
    db.insertMission(makeMission("q", "map", "2026-01-01T00:00:00.000Z", RunStatus::Queued));
    db.insertMission(makeMission("r", "map", "2026-01-01T00:00:01.000Z", RunStatus::Queued));
    db.updateMission("r", RunStatus::Running, "");
    db.insertMission(makeMission("s", "map", "2026-01-01T00:00:02.000Z", RunStatus::Queued));
    db.updateMission("s", RunStatus::Succeeded, "", json{{"ok", true}});
    db.insertMission(makeMission("f", "map", "2026-01-01T00:00:03.000Z", RunStatus::Queued));
    db.updateMission("f", RunStatus::Failed, "boom");
  }  // the server "dies" (clean close here; the kill -9 case is tested below)

  Database db(t.db());
  CHECK(db.markUnfinishedInterrupted() == 2);
  auto q = db.getMission("q");
  auto r = db.getMission("r");
  REQUIRE(q.has_value());
  REQUIRE(r.has_value());
  CHECK(q->status == RunStatus::Interrupted);
  CHECK(q->message == "server restarted while the mission was queued");
  CHECK(std::regex_match(q->finishedAt, kIsoRe));
  CHECK(r->status == RunStatus::Interrupted);
  CHECK(r->message == "server restarted while the mission was running");
  CHECK_FALSE(r->startedAt.empty());
  CHECK(std::regex_match(r->finishedAt, kIsoRe));
  CHECK(db.getMission("s")->status == RunStatus::Succeeded);
  CHECK(db.getMission("s")->metrics == json{{"ok", true}});
  CHECK(db.getMission("f")->status == RunStatus::Failed);
  CHECK(db.getMission("f")->message == "boom");
  CHECK(db.markUnfinishedInterrupted() == 0);
}

TEST_CASE("database: WAL mode and schema version") {
  TempDir t;
  {
    Database db(t.db());
    db.insertMap(makeMap("m", "2026-01-01T00:00:00.000Z"));
    CHECK(fs::exists(t.db() + "-wal"));
    CHECK(rawQuery(t.db(), "PRAGMA journal_mode") == "wal");
    CHECK(rawQuery(t.db(), "SELECT MAX(version) FROM schema_version") == "5");
    CHECK(rawQuery(t.db(), "SELECT COUNT(*) FROM schema_version") == "5");  // 1, 1 -> 2, 2 -> 3, 3 -> 4, 4 -> 5
  }
  {
    Database again(t.db());  // reopening an existing schema is a no-op
    CHECK(again.getMap("m").has_value());
  }
  CHECK(rawQuery(t.db(), "SELECT COUNT(*) FROM schema_version") == "5");

  // A database written by a newer server is refused rather than misread.
  rawQuery(t.db(), "INSERT INTO schema_version(version) VALUES (6)");
  try {
    Database newer(t.db());
    FAIL("expected an exception");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("schema version 6") != std::string::npos);
  }
}

TEST_CASE("database: a version 1 file migrates to 5, its runs labelled with their request's name, its maps at version 1") {
  TempDir t;
  {  // The version 1 schema as servers before the migration wrote it.
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open(t.db().c_str(), &db) == SQLITE_OK);
    REQUIRE(sqlite3_exec(db, R"sql(
      CREATE TABLE schema_version(version INTEGER NOT NULL); INSERT INTO schema_version VALUES (1);
      CREATE TABLE maps(id TEXT PRIMARY KEY, name TEXT NOT NULL, created_at TEXT NOT NULL,
                        meta TEXT NOT NULL DEFAULT 'null');
      CREATE TABLE pdms(id TEXT PRIMARY KEY, map_id TEXT NOT NULL REFERENCES maps(id) ON DELETE CASCADE,
                        name TEXT NOT NULL, created_at TEXT NOT NULL, meta TEXT NOT NULL DEFAULT 'null');
      CREATE TABLE missions(id TEXT PRIMARY KEY, map_id TEXT NOT NULL, pdm_id TEXT NOT NULL DEFAULT '',
        planner TEXT NOT NULL, spec TEXT NOT NULL DEFAULT 'null', status TEXT NOT NULL,
        message TEXT NOT NULL DEFAULT '', created_at TEXT NOT NULL, started_at TEXT, finished_at TEXT,
        metrics TEXT);
      INSERT INTO maps VALUES ('m1', 'gale', '2026-01-01T00:00:00.000Z', 'null');
      INSERT INTO missions(id, map_id, planner, spec, status, created_at, metrics) VALUES
        ('a', 'm1', 'coverage', '{"name":"old run","rovers":[]}', 'succeeded', '2026-01-02T00:00:00.000Z', '{"coverage":0.9}'),
        ('b', 'gone', 'coverage', '{"rovers":[]}', 'failed', '2026-01-03T00:00:00.000Z', NULL);
    )sql", nullptr, nullptr, nullptr) == SQLITE_OK);
    sqlite3_close(db);
  }
  Database db(t.db());
  CHECK(rawQuery(t.db(), "SELECT MAX(version) FROM schema_version") == "5");
  // The map kept its row and is version 1; a rename names it.
  auto gale = db.getMap("m1");
  REQUIRE(gale);
  CHECK(gale->name == "gale");
  CHECK(gale->version == 1);
  CHECK(db.renameMap("m1", "gale crater", 2).cas == Cas::Stale);
  CHECK(db.renameMap("nope", "x", 1).cas == Cas::Missing);
  const rover::store::MapRename renamed = db.renameMap("m1", "gale crater", 1);
  CHECK(renamed.cas == Cas::Done);
  CHECK(renamed.takenBy.empty());
  CHECK(db.getMap("m1")->version == 2);
  auto a = db.getMission("a");
  REQUIRE(a);
  CHECK(a->label == "old run");
  CHECK(a->mapName == "gale crater");
  CHECK(a->metrics["coverage"] == 0.9);
  auto b = db.getMission("b");
  REQUIRE(b);
  CHECK(b->label.empty());
  CHECK(b->mapName.empty());
  CHECK(db.setMissionLabel("b", "retry"));
  CHECK(db.listMissions()[0].label == "retry");
  CHECK(db.deleteMission("a"));
  CHECK_FALSE(db.deleteMission("a"));
  CHECK(db.countMissions() == 1);
}

TEST_CASE("database: cannot open a path under a regular file") {
  TempDir t;
  std::ofstream(t.path / "file") << "x";
  CHECK_THROWS_AS(Database((t.path / "file" / "x.db").string()), std::runtime_error);
}

TEST_CASE("database: concurrent inserts from 4 threads") {
  TempDir t;
  Database db(t.db());
  constexpr int kThreads = 4, kPerThread = 50;
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int th = 0; th < kThreads; ++th) {
    threads.emplace_back([&, th] {
      try {
        for (int i = 0; i < kPerThread; ++i) {
          const std::string id = numbered(numbered("t", th) + "-", i);
          db.insertMission(makeMission(id, "map", rover::store::nowIso()));
          if (i % 10 == 0) db.updateMission(id, RunStatus::Running, "");
          (void)db.listMissions();
        }
      } catch (...) {
        ++failures;
      }
    });
  }
  for (auto& th : threads) th.join();
  CHECK(failures.load() == 0);
  const auto all = db.listMissions();
  CHECK(all.size() == kThreads * kPerThread);
  std::set<std::string> ids;
  for (const auto& m : all) ids.insert(m.id);
  CHECK(ids.size() == kThreads * kPerThread);
  for (std::size_t i = 1; i < all.size(); ++i) CHECK(all[i - 1].createdAt >= all[i].createdAt);
}

TEST_CASE("database: a committed row survives kill -9 of the writer") {
  TempDir t;
  const std::string path = t.db();
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    // Child: open, write, and die without closing anything.
    try {
      Database db(path);
      db.insertMap(makeMap("survivor", "2026-01-01T00:00:00.000Z"));
      db.insertMission(makeMission("mission", "survivor", "2026-01-01T00:00:00.000Z", RunStatus::Running));
      raise(SIGKILL);  // with the connection still open
    } catch (...) {
      _exit(3);
    }
    _exit(4);  // not reached
  }
  int status = 0;
  REQUIRE(waitpid(pid, &status, 0) == pid);
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGKILL);
  CHECK(fs::exists(path + "-wal"));  // the rows live in the WAL, never checkpointed

  Database db(path);
  auto m = db.getMap("survivor");
  REQUIRE(m.has_value());
  CHECK(m->meta == makeMap("survivor", "").meta);
  CHECK(db.markUnfinishedInterrupted() == 1);
  CHECK(db.getMission("mission")->message == "server restarted while the mission was running");
  CHECK(rawQuery(path, "PRAGMA integrity_check") == "ok");
}

TEST_CASE("database: every acknowledged write survives kill -9 mid-stream") {
  TempDir t;
  const std::string path = t.db();
  int fds[2];
  REQUIRE(pipe(fds) == 0);
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    close(fds[0]);
    try {
      Database db(path);
      for (int i = 0; i < 1000000; ++i) {
        db.insertMission(makeMission(numbered("m", i), "map", rover::store::nowIso()));
        const std::int32_t ack = i;
        if (write(fds[1], &ack, sizeof ack) != sizeof ack) _exit(5);
      }
    } catch (...) {
      _exit(3);
    }
    _exit(0);
  }
  close(fds[1]);
  std::int32_t last = -1;
  for (int got = 0; got < 100; ++got) {
    std::int32_t ack = 0;
    REQUIRE(read(fds[0], &ack, sizeof ack) == sizeof ack);
    last = ack;
  }
  kill(pid, SIGKILL);  // in the middle of the next writes
  int status = 0;
  REQUIRE(waitpid(pid, &status, 0) == pid);
  close(fds[0]);
  CHECK(WIFSIGNALED(status));

  CHECK(rawQuery(path, "PRAGMA integrity_check") == "ok");
  Database db(path);
  for (int i = 0; i <= last; ++i) {
    if (!db.getMission(numbered("m", i)).has_value()) {
      FAIL("acknowledged mission " << numbered("m", i) << " is missing");
    }
  }
  CHECK(db.listMissions().size() >= static_cast<std::size_t>(last + 1));
}

TEST_CASE("database: nowIso is UTC with milliseconds") {
  const std::string a = rover::store::nowIso();
  CHECK(std::regex_match(a, kIsoRe));
  // It moves on by the millisecond the format shows (ISO strings order as the times they name).
  rover::test::waitUntil([&] { return rover::store::nowIso() > a; }, "nowIso to move past " + a);
}

// ---- DataDir ----------------------------------------------------------------------------------

TEST_CASE("data dir: creates its layout, ids are 16 lowercase hex") {
  TempDir t;
  const std::string root = (t.path / "data" / "nested").string();
  DataDir dir(root);
  CHECK(dir.root() == root);
  for (const char* sub : {"maps", "pdms", "missions", "tmp"}) CHECK(fs::is_directory(fs::path(root) / sub));
  CHECK(dir.databasePath() == (fs::path(root) / "roverplan.db").string());
  CHECK(dir.mapDir("abc") == (fs::path(root) / "maps" / "abc").string());
  CHECK(dir.pdmDir("abc") == (fs::path(root) / "pdms" / "abc").string());
  CHECK(dir.missionDir("abc") == (fs::path(root) / "missions" / "abc").string());
  CHECK(dir.tmpDir() == (fs::path(root) / "tmp").string());
  CHECK(listNames(root).size() == 4);  // the write probe was removed
  CHECK(listNames(dir.tmpDir()).empty());

  const std::regex hex("^[0-9a-f]{16}$");
  std::set<std::string> ids;
  for (int i = 0; i < 1000; ++i) {
    const std::string id = DataDir::newId();
    CHECK(std::regex_match(id, hex));
    ids.insert(id);
  }
  CHECK(ids.size() == 1000);

  DataDir again(root);  // an existing layout is fine
  CHECK(fs::is_directory(again.tmpDir()));
}

TEST_CASE("data dir: an unwritable path throws a clear error") {
  TempDir t;
  const fs::path file = t.path / "plain-file";
  std::ofstream(file) << "not a folder";
  try {
    DataDir dir((file / "data").string());
    FAIL("expected an exception");
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    CHECK(msg.find("data directory") != std::string::npos);
    CHECK(msg.find((file / "data").string()) != std::string::npos);
  }
  CHECK_THROWS_AS(DataDir(file.string()), std::runtime_error);  // a file, not a folder

  if (geteuid() != 0) {  // root ignores permission bits
    const fs::path ro = t.path / "read-only";
    fs::create_directories(ro);
    DataDir ok(ro.string());
    fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
    try {
      DataDir dir(ro.string());
      FAIL("expected an exception");
    } catch (const std::runtime_error& e) {
      CHECK(std::string(e.what()).find("not writable") != std::string::npos);
    }
    fs::permissions(ro, fs::perms::owner_all);
  }
}

TEST_CASE("data dir: writeFileAtomic writes whole files and leaves no temp files") {
  TempDir t;
  const fs::path target = t.path / "result.json";
  std::string big(8 << 20, '\0');
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>('a' + (i * 7919) % 26);
  DataDir::writeFileAtomic(target.string(), big);
  CHECK(readFile(target) == big);
  CHECK(listNames(t.path) == std::vector<std::string>{"result.json"});

  DataDir::writeFileAtomic(target.string(), "small");  // replaces
  CHECK(readFile(target) == "small");
  DataDir::writeFileAtomic(target.string(), "");
  CHECK(fs::exists(target));
  CHECK(fs::file_size(target) == 0);
  CHECK(listNames(t.path) == std::vector<std::string>{"result.json"});

  // A missing folder fails and creates nothing.
  CHECK_THROWS_AS(DataDir::writeFileAtomic((t.path / "no" / "x.json").string(), "x"),
                  std::runtime_error);
  CHECK_FALSE(fs::exists(t.path / "no"));
}

TEST_CASE("data dir: readFileUpTo reads whole files up to a size, nothing else") {
  TempDir t;
  const fs::path f = t.path / "tile.png";
  const std::string bytes(4096 + 17, 'p');
  DataDir::writeFileAtomic(f.string(), bytes, false);
  CHECK(DataDir::readFileUpTo(f.string(), bytes.size()) == bytes);  // exactly the cap
  CHECK_FALSE(DataDir::readFileUpTo(f.string(), bytes.size() - 1));  // one byte over
  // Just written, so in the page cache: a cached-only read gets it too.
  CHECK(DataDir::readFileUpTo(f.string(), 1 << 20, DataDir::Read::CachedOnly) == bytes);
  CHECK_FALSE(DataDir::readFileUpTo((t.path / "absent.png").string(), 1 << 20));
  CHECK_FALSE(DataDir::readFileUpTo(t.path.string(), 1 << 20));  // a folder is no file
  DataDir::writeFileAtomic(f.string(), "", false);
  CHECK(DataDir::readFileUpTo(f.string(), 1 << 20) == std::string());
}

TEST_CASE("data dir: a reader never sees a partial file during writeFileAtomic") {
  TempDir t;
  const fs::path target = t.path / "f.bin";
  const std::string a(2 << 20, 'a'), b(3 << 20, 'b');
  DataDir::writeFileAtomic(target.string(), a);
  std::atomic<bool> done{false};
  std::atomic<int> bad{0}, reads{0};
  std::thread reader([&] {
    while (!done.load()) {
      const std::string s = readFile(target);
      if (s != a && s != b) ++bad;
      ++reads;
    }
  });
  for (int i = 0; i < 20; ++i) DataDir::writeFileAtomic(target.string(), i % 2 ? a : b);
  done = true;
  reader.join();
  CHECK(bad.load() == 0);
  CHECK(reads.load() > 0);
  CHECK(listNames(t.path) == std::vector<std::string>{"f.bin"});
}

TEST_CASE("data dir: staging then commitDir, refusing an existing target") {
  TempDir t;
  DataDir dir((t.path / "data").string());
  const std::string staged = dir.stagingDir();
  CHECK(fs::is_directory(staged));
  CHECK(fs::path(staged).parent_path() == fs::path(dir.tmpDir()));
  CHECK(dir.stagingDir() != staged);
  DataDir::writeFileAtomic((fs::path(staged) / "dem.tif").string(), "raster bytes");
  fs::create_directories(fs::path(staged) / "layers");
  DataDir::writeFileAtomic((fs::path(staged) / "layers" / "slope.bin").string(), "slope");

  const std::string id = DataDir::newId();
  dir.commitDir(staged, dir.mapDir(id));
  CHECK_FALSE(fs::exists(staged));
  CHECK(readFile(fs::path(dir.mapDir(id)) / "dem.tif") == "raster bytes");
  CHECK(readFile(fs::path(dir.mapDir(id)) / "layers" / "slope.bin") == "slope");

  // An existing target (even an empty folder, which rename(2) would replace) is refused.
  const std::string staged2 = dir.stagingDir();
  DataDir::writeFileAtomic((fs::path(staged2) / "other").string(), "new");
  CHECK_THROWS_AS(dir.commitDir(staged2, dir.mapDir(id)), std::runtime_error);
  CHECK(readFile(fs::path(dir.mapDir(id)) / "dem.tif") == "raster bytes");
  fs::create_directories(dir.pdmDir("empty"));
  CHECK_THROWS_AS(dir.commitDir(staged2, dir.pdmDir("empty")), std::runtime_error);
  CHECK(fs::exists(fs::path(staged2) / "other"));  // the staged folder is left in place

  CHECK_THROWS_AS(dir.commitDir(dir.tmpDir() + "/missing", dir.pdmDir("x")), std::runtime_error);
}

TEST_CASE("data dir: cleanTmp empties tmp but keeps it, removeTree") {
  TempDir t;
  DataDir dir((t.path / "data").string());
  const std::string s1 = dir.stagingDir();
  DataDir::writeFileAtomic((fs::path(s1) / "a").string(), "x");
  fs::create_directories(fs::path(s1) / "deep" / "er");
  DataDir::writeFileAtomic((fs::path(dir.tmpDir()) / "upload.part").string(), "partial");
  dir.stagingDir();
  CHECK(listNames(dir.tmpDir()).size() == 3);

  dir.cleanTmp();
  CHECK(fs::is_directory(dir.tmpDir()));
  CHECK(listNames(dir.tmpDir()).empty());
  dir.cleanTmp();  // idempotent

  const std::string staged = dir.stagingDir();
  DataDir::writeFileAtomic((fs::path(staged) / "f").string(), "x");
  DataDir::removeTree(staged);
  CHECK_FALSE(fs::exists(staged));
  DataDir::removeTree(staged);  // absent: no error
  DataDir::removeTree((t.path / "never" / "there").string());
}

TEST_CASE("database: a map's keep-out zones are replaced on write and go with the map") {
  TempDir t;
  Database db(t.db());
  db.insertMap(makeMap("m", "2026-01-01T00:00:00.000Z"));
  CHECK_FALSE(db.getZones("m"));
  const nlohmann::json one{{"type", "FeatureCollection"}, {"features", nlohmann::json::array({1})}};
  const nlohmann::json none{{"type", "FeatureCollection"}, {"features", nlohmann::json::array()}};
  CHECK(db.setZones("m", one));
  CHECK(*db.getZones("m") == one);
  CHECK(db.setZones("m", none));
  CHECK(*db.getZones("m") == none);
  CHECK_FALSE(db.setZones("absent", one));  // no map, no row
  CHECK_FALSE(db.getZones("absent"));
  CHECK(db.deleteMap("m"));
  CHECK_FALSE(db.getZones("m"));
  CHECK(rawQuery(t.db(), "SELECT COUNT(*) FROM zones") == "0");
}

TEST_CASE("database: versioned zone sets and PDMs: compare-and-set, bounded history gone with its object") {
  TempDir t;
  Database db(t.db());
  db.insertMap(makeMap("m", "2026-01-01T00:00:00.000Z"));
  ZoneSet set{nlohmann::json{{"type", "FeatureCollection"}, {"features", nlohmann::json::array()}}, 0, 1};
  CHECK(db.putZoneSet("m", set, 1, "ada") == Cas::Stale);  // nothing stored yet: version 0
  for (long long v = 0; v < kHistoryPerObject + 5; ++v) REQUIRE(db.putZoneSet("m", set, v, "ada") == Cas::Done);
  CHECK(db.putZoneSet("m", set, 3, "bob") == Cas::Stale);
  CHECK(db.putZoneSet("absent", set, 0, "bob") == Cas::Missing);
  CHECK(db.getZoneSet("m")->version == kHistoryPerObject + 5);
  const auto hist = db.history("zones", "m");
  REQUIRE(hist.size() == static_cast<std::size_t>(kHistoryPerObject));
  CHECK(hist.front().version == kHistoryPerObject + 5);
  CHECK(hist.front().by == "ada");
  CHECK_FALSE(db.historyVersion("zones", "m", 5));

  PdmRecord p{"p", "m", "pdm", "2026-01-01T00:00:00.000Z", {{"kind", "gaussians"}}, 1};
  db.insertPdm(p, "ada");
  CHECK(db.getPdm("p")->version == 1);
  p.name = "renamed";
  bool wrote = false;
  CHECK(db.updatePdm(p, 2, {{"name", "renamed"}}, "bob", [&] { wrote = true; }) == Cas::Stale);
  CHECK_FALSE(wrote);  // a refused write runs nothing
  CHECK(db.updatePdm(p, 1, {{"name", "renamed"}}, "bob", [&] { wrote = true; }) == Cas::Done);
  CHECK(wrote);
  CHECK(db.getPdm("p")->version == 2);
  CHECK(db.history("pdm", "p").size() == 2);
  CHECK(db.historyVersion("pdm", "p", 1)->by == "ada");
  CHECK(db.deletePdm("p"));
  CHECK(db.history("pdm", "p").empty());
  CHECK(db.deleteMap("m"));
  CHECK(rawQuery(t.db(), "SELECT COUNT(*) FROM history") == "0");

  db.setCounter("event_seq", 41);
  CHECK(db.counter("event_seq") == 41);
  CHECK(db.counter("none") == 0);
}
