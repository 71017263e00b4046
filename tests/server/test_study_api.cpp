// /api/studies over loopback (issue 12): launch, WebSocket progress frames, summary, runs.csv,
// study.sqlite, cancel, delete, bad specs (400 naming the field), the bounds, the priority below
// missions, a run opened as a mission, and a restart that resumes a study with only its missing runs.
#include <doctest/doctest.h>

#include <sqlite3.h>

#include <atomic>
#include <set>
#include <sstream>

#include "server/studies/studies.hpp"
#include "server/studies/study_manager.hpp"
#include "api_server.hpp"
#include "event_client.hpp"

namespace rover::test {

namespace {

using nlohmann::json;

// The API with studies, as `roverplan serve` builds it; `busy` stands for the missions' claim and
// `busyAsked` counts how often the studies have asked for it.
struct StudyServer {
  std::shared_ptr<std::atomic<bool>> busy = std::make_shared<std::atomic<bool>>(false);
  std::shared_ptr<std::atomic<int>> busyAsked = std::make_shared<std::atomic<int>>(0);
  ApiServer api;
  studies::StudyManager studies;
  explicit StudyServer(const std::string& data)
      : api(data, [] {
          ApiServerOptions o;
          o.start = false;
          return o;
        }()),
        studies(api.dir, [b = busy, n = busyAsked] {
          ++*n;
          return b->load();
        }) {
    api.ctx.studies = &studies;
    api::addStudyRoutes(api.router, api.ctx);
    api.start();
  }
  ~StudyServer() { studies.stop(); }
  json study(const std::string& id) { return api.get("/api/studies/" + id).json(); }
  // Waits until the study has ended and returns its state; FAILs on a hang.
  json waitEnded(const std::string& id) {
    json s;
    waitUntil(
        [&] {
          s = study(id);
          return isFinal(parseEnum<RunStatus>(s["status"].get<std::string>()).value_or(RunStatus::Queued));
        },
        rover::test::kHangDeadline, "study " + id + " to end");
    return s;
  }
  // Waits until the study has committed its first runs.
  void waitFirstRuns(const std::string& id) {
    waitUntil([&] { return study(id)["runs_done"].get<int>() > 0; }, "study " + id + " to commit runs");
  }
};

// A study of fast runs: coverage on 30×30 random grids, two patterns.
json tinySpec(int runs) {
  return {{"name", "tiny"},
          {"planner", "coverage"},
          {"runs", runs},
          {"worlds", {{{"name", "30x30"}, {"grid", {{"rows", 30}, {"cols", 30}}}}}},
          {"grid", {{"pattern", {"spiral", "boustrophedon"}}}},
          {"levels", {0.9, 1.0}}};
}

std::vector<std::string> csvLines(const std::string& csv) {
  std::vector<std::string> lines;
  std::istringstream in(csv);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::set<long long> runIndices(const std::string& csv) {
  std::set<long long> out;
  const auto lines = csvLines(csv);
  for (std::size_t i = 1; i < lines.size(); ++i) out.insert(std::stoll(lines[i].substr(0, lines[i].find(','))));
  return out;
}

}  // namespace

TEST_CASE("studies API: launch, progress frames, summary, runs.csv, study.sqlite, delete") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  const HttpResult launched = s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 3}});
  REQUIRE(launched.status == 202);
  const json st = launched.json();
  const std::string id = st["id"];
  CHECK(st["runs_total"] == 12);  // 4 variants × 3 runs
  CHECK(st["links"]["stream"] == "/api/studies/" + id + "/stream");

  // The stream: a snapshot, then progress, then done with the final summary.
  const auto frames = readAllFrames(s.api.port(), "/api/studies/" + id + "/stream");
  REQUIRE(frames.size() >= 2);
  const json first = json::parse(frames.front().data), last = json::parse(frames.back().data);
  CHECK(first["type"] == "snapshot");
  CHECK(first["study"]["id"] == id);
  CHECK(last["type"] == "done");
  CHECK(last["status"] == "succeeded");
  CHECK(last["runs_done"] == 12);
  CHECK(last["summary"]["rows"].size() > 0);
  for (std::size_t i = 1; i + 1 < frames.size(); ++i) {
    const json f = json::parse(frames[i].data);
    CHECK(f["type"] == "progress");
    CHECK(f["runs_total"] == 12);
    CHECK(f["runs_done"].get<int>() <= 12);
  }

  const json one = s.study(id);
  CHECK(one["status"] == "succeeded");
  CHECK(one["spec"]["name"] == "laine-fig6");
  CHECK(one["configurations"].size() == 4);
  CHECK(one["summary"]["runs_done"] == 12);
  bool hasRatio = false;
  for (const auto& r : one["summary"]["rows"]) hasRatio |= r["metric"] == "path_length_ratio@100%";
  CHECK(hasRatio);

  const json list = s.api.get("/api/studies").json();
  REQUIRE(list.size() == 1);
  CHECK(list[0]["id"] == id);

  const HttpResult csv = s.api.get("/api/studies/" + id + "/runs.csv");
  CHECK(csv.status == 200);
  CHECK(csv.headers.at("Content-Type") == "text/csv");
  CHECK(csvLines(csv.body).size() == 13);
  CHECK(runIndices(csv.body).size() == 12);

  const HttpResult db = s.api.get("/api/studies/" + id + "/study.sqlite");
  CHECK(db.status == 200);
  CHECK(db.body.rfind("SQLite format 3", 0) == 0);

  // A grid-world run is no mission, and says why.
  const json run = s.api.get("/api/studies/" + id + "/runs/5").json();
  CHECK(run["mission"].is_null());
  CHECK(run["mission_unavailable"].get<std::string>().find("random obstacle grid") != std::string::npos);
  checkError(s.api.post("/api/studies/" + id + "/runs/5/mission", ""), 409, "not_a_mission", "run");
  checkError(s.api.get("/api/studies/" + id + "/runs/12"), 404, "run");
  checkError(s.api.get("/api/studies/" + id + "/runs/-1"), 404, "run");

  // Ended: DELETE removes it with its files.
  CHECK(request(s.api.port(), "DELETE", "/api/studies/" + id).status == 200);
  checkError(s.api.get("/api/studies/" + id), 404, "id");
  CHECK(!std::filesystem::exists(tmp.path / "data" / "studies" / id));
  checkError(s.api.get("/api/studies/nope/runs.csv"), 404, "id");
}

TEST_CASE("studies API: GET serves the summary kept with the study, not a pass over its runs") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  const HttpResult launched = s.api.postJson("/api/studies", tinySpec(4));
  REQUIRE(launched.status == 202);
  const std::string id = launched.json()["id"];
  const json ended = s.waitEnded(id);
  REQUIRE(ended["status"] == "succeeded");
  const json summary = ended["summary"];
  CHECK(summary["runs_done"] == 8);
  // The published summary is the database's.
  const std::string dbPath = (tmp.path / "data" / "studies" / id / "study.sqlite").string();
  {
    studies::StudyDb db = studies::StudyDb::open(dbPath);
    CHECK(studies::toJson(db.summary()).dump() == summary.dump());
  }
  CHECK(std::filesystem::exists(tmp.path / "data" / "studies" / id / "summary.json"));
  // Emptied behind the server's back, the runs table no longer gives that summary; the GET still
  // does: it reads no run.
  sqlite3* raw = nullptr;
  REQUIRE(sqlite3_open(dbPath.c_str(), &raw) == SQLITE_OK);
  CHECK(sqlite3_exec(raw, "DELETE FROM runs", nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_close(raw);
  CHECK(s.study(id)["summary"].dump() == summary.dump());
}

TEST_CASE("studies API: bad specs answer 400 naming the field, bounds") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  checkError(s.api.postJson("/api/studies", {{"planner", "coverage"}, {"worlds", {{{"grid", {{"rows", 1}}}}}}}), 400,
             "worlds[0].grid.rows");
  checkError(s.api.postJson("/api/studies", {{"preset", "nope"}}), 400, "preset");
  checkError(s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 0}}), 400, "runs");
  checkError(s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"threads", 4}}), 400, "threads");
  // No file a request names is read.
  checkError(s.api.postJson("/api/studies", {{"planner", "team-search"}, {"worlds", {{{"dem", "/etc/passwd"}}}}}), 400,
             "worlds[0].dem");
  json params = tinySpec(1);
  params["grid"]["patern"] = {"spiral"};
  CHECK(s.api.postJson("/api/studies", params).status == 400);
  checkError(s.api.post("/api/studies", "{not json"), 400, "body");
  // Runs per study.
  checkError(s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 60000}}), 400, "too_many_runs", "runs");
  json threaded = tinySpec(1);
  threaded["mission_threads"] = 4;
  checkError(s.api.postJson("/api/studies", threaded), 400, "mission_threads");
  CHECK(s.api.get("/api/studies").json().empty());

  // Studies queued or running: kMaxActive, then 429. While the missions hold the machine (busy),
  // no run is taken.
  s.busy->store(true);
  std::vector<std::string> ids;
  for (std::size_t k = 0; k < studies::kMaxActive; ++k) {
    const HttpResult r = s.api.postJson("/api/studies", tinySpec(5));
    REQUIRE(r.status == 202);
    ids.push_back(r.json()["id"]);
  }
  const HttpResult full = s.api.postJson("/api/studies", tinySpec(5));
  CHECK(full.status == 429);
  CHECK(full.headers.count("Retry-After") == 1);
  // The running study has asked twice since and was told to wait both times: no run taken.
  const int asked = s.busyAsked->load();
  waitUntil([&] { return s.busyAsked->load() >= asked + 2; }, "the study to ask whether the missions are busy");
  CHECK(s.study(ids[0])["runs_done"] == 0);

  // Cancel a queued one: it ends at once; then it can be deleted.
  CHECK(request(s.api.port(), "DELETE", "/api/studies/" + ids[3]).status == 202);
  CHECK(s.study(ids[3])["status"] == "cancelled");
  CHECK(request(s.api.port(), "DELETE", "/api/studies/" + ids[3]).status == 200);

  // The missions let go: the queued studies run, one after the other.
  s.busy->store(false);
  for (std::size_t k = 0; k < 3; ++k) {
    const json e = s.waitEnded(ids[k]);
    CHECK(e["status"] == "succeeded");
    CHECK(e["runs_done"] == 10);
  }
}

TEST_CASE("studies API: cancelling a running study keeps the runs done") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  const std::string id = s.api.postJson("/api/studies", tinySpec(20000)).json()["id"];
  s.waitFirstRuns(id);
  CHECK(request(s.api.port(), "DELETE", "/api/studies/" + id).status == 202);
  const json e = s.waitEnded(id);
  CHECK(e["status"] == "cancelled");
  const int done = e["runs_done"];
  CHECK(done > 0);
  CHECK(done < 40000);
  CHECK(runIndices(s.api.get("/api/studies/" + id + "/runs.csv").body).size() == static_cast<std::size_t>(done));
}

TEST_CASE("studies API: a restart resumes an unfinished study with only its missing runs") {
  TempDir tmp;
  const json spec = tinySpec(1500);
  std::string id;
  std::size_t doneAtStop = 0;
  {
    StudyServer s(tmp.str("data"));
    id = s.api.postJson("/api/studies", spec).json()["id"];
    s.waitFirstRuns(id);
  }  // the server stops mid-study
  {
    studies::StudyDb db = studies::StudyDb::open(tmp.str("data/studies/" + id + "/study.sqlite"));
    doneAtStop = db.runCount();
  }
  CHECK(doneAtStop > 0);
  if (doneAtStop >= 3000) MESSAGE("the study finished before the stop: the resume is not exercised");
  StudyServer again(tmp.str("data"));
  const json e = again.waitEnded(id);
  CHECK(e["status"] == "succeeded");
  CHECK(e["runs_done"] == 3000);
  const std::string csv = again.api.get("/api/studies/" + id + "/runs.csv").body;
  CHECK(csvLines(csv).size() == 3001);  // no run twice
  CHECK(runIndices(csv).size() == 3000);

  // The rows are those of one uninterrupted run of the same spec.
  studies::StudyDb resumed = studies::StudyDb::open(tmp.str("data/studies/" + id + "/study.sqlite"));
  studies::StudyDb fresh = studies::StudyDb::open(":memory:");
  studies::RunOptions o;
  o.threads = 2;
  studies::StudyRunner(studies::parseStudySpec(spec)).run(fresh, o);
  std::ostringstream a, b;
  resumed.dump(a);
  fresh.dump(b);
  CHECK(a.str() == b.str());
}

TEST_CASE("studies API: a run on the default map's world opens as the same mission") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  json spec{{"name", "mars"},
            {"planner", "coverage"},
            {"runs", 1},
            {"worlds", {{{"name", "mars"}, {"terrain", json::object()}}}},
            {"params", {{"coverage", 0.05}}}};
  const std::string id = s.api.postJson("/api/studies", spec).json()["id"];
  REQUIRE(s.waitEnded(id)["status"] == "succeeded");
  const json run = s.api.get("/api/studies/" + id + "/runs/0").json();
  REQUIRE(run["mission"].is_object());
  CHECK(run["mission"]["map"] == s.api.defaultMap());
  const HttpResult m = s.api.post("/api/studies/" + id + "/runs/0/mission", "");
  REQUIRE(m.status == 202);
  const json mission = s.api.waitFinished(m.json()["id"], 60);
  CHECK(mission["status"] == "succeeded");
  const auto lines = csvLines(s.api.get("/api/studies/" + id + "/runs.csv").body);
  REQUIRE(lines.size() == 2);
  // The run's moves and distance, as the mission's.
  std::vector<std::string> head, row;
  for (auto [line, out] : {std::pair{&lines[0], &head}, std::pair{&lines[1], &row}}) {
    std::istringstream in(*line);
    for (std::string c; std::getline(in, c, ',');) out->push_back(c);
  }
  for (const char* key : {"moves", "distance_m", "coverage"}) {
    const auto k = std::find(head.begin(), head.end(), key) - head.begin();
    REQUIRE(k < static_cast<long>(row.size()));
    CHECK(std::stod(row[static_cast<std::size_t>(k)]) == doctest::Approx(mission["metrics"][key].get<double>()).epsilon(1e-12));
  }
}

// Issue 27: a team run opened as a mission reproduces its row exactly: the same world (the study's
// synthetic Mars read back as the stored default map is), PDM, seed, starts and parameters give
// the same metrics to the last digit (before: mean trajectory 41.30 m in the row, 35.48 m as a
// mission, from the cell width the map loader measures).
TEST_CASE("studies API: a team run opened as a mission gives the row's metrics exactly") {
  TempDir tmp;
  StudyServer s(tmp.str("data"));
  json spec{{"name", "eq"},
            {"planner", "team-search"},
            {"runs", 1},
            {"worlds", {{{"name", "mars600"}, {"terrain", json::object()}}}},
            {"rovers", 2},
            {"starts", "formation"},
            {"pdm", {{"random_gaussians", 4}}},
            {"params", {{"targets", 6}}},
            {"mission_threads", 1}};
  const std::string id = s.api.postJson("/api/studies", spec).json()["id"];
  REQUIRE(s.waitEnded(id)["status"] == "succeeded");
  const HttpResult m = s.api.post("/api/studies/" + id + "/runs/0/mission", "");
  REQUIRE(m.status == 202);
  const std::string missionId = m.json()["id"];
  s.api.waitFinished(missionId);
  const json result = s.api.get("/api/missions/" + missionId + "/result.json").json();
  const auto lines = csvLines(s.api.get("/api/studies/" + id + "/runs.csv").body);
  REQUIRE(lines.size() == 2);
  std::vector<std::string> head, row;
  for (auto [line, out] : {std::pair{&lines[0], &head}, std::pair{&lines[1], &row}}) {
    std::istringstream in(*line);
    for (std::string c; std::getline(in, c, ',');) out->push_back(c);
  }
  int compared = 0;
  for (std::size_t k = 0; k < head.size() && k < row.size(); ++k) {
    const std::string& key = head[k];
    if (key == "plan_wall_s" || row[k].empty() || !result["metrics"].contains(key)) continue;
    const json& v = result["metrics"][key];
    if (!v.is_number()) continue;
    INFO(key << ": row " << row[k] << ", mission " << v.dump());
    CHECK(std::stod(row[k]) == v.get<double>());
    ++compared;
  }
  MESSAGE(compared << " metrics compared; mean_trajectory_m " << result["metrics"]["mean_trajectory_m"].dump());
  CHECK(compared > 10);
}

TEST_CASE("splitCommandLine: words, quotes, escapes, no shell") {
  using studies::splitCommandLine;
  CHECK(splitCommandLine("") == std::vector<std::string>{});
  CHECK(splitCommandLine("mpirun -np 16 --hostfile H") == std::vector<std::string>{"mpirun", "-np", "16", "--hostfile", "H"});
  CHECK(splitCommandLine("  env  'A=b c' \"d\\\"e\" f\\ g ") == std::vector<std::string>{"env", "A=b c", "d\"e", "f g"});
  CHECK(splitCommandLine("echo ''") == std::vector<std::string>{"echo", ""});
  CHECK(splitCommandLine("a;rm -rf x") == std::vector<std::string>{"a;rm", "-rf", "x"});  // ';' is a character
  CHECK_THROWS(splitCommandLine("mpirun 'open"));
}

TEST_CASE("studies API: names follow the one name rule, runs are addressed by canonical indices only") {
  TempDir d;
  // One name rule for every named object (issue 22): a right-to-left override that would show
  // "evil\u202Etxt.exe" as "evilexe.txt" is refused here as in map and mission names.
  StudyServer s(d.str("data"));
  checkError(s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 3}, {"name", "evil\u202Etxt.exe"}}), 400,
             "name");
  checkError(s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 3}, {"name", std::string(201, 'a')}}),
             400, "name");
  const auto launched = s.api.postJson("/api/studies", {{"preset", "laine-fig6"}, {"runs", 3}, {"name", "fig. 6 \u00e9t\u00e9"}});
  REQUIRE(launched.status == 202);
  const std::string id = launched.json()["id"];
  CHECK(s.api.get("/api/studies/" + id + "/runs/1").status == 200);
  for (const char* run : {"1e0", "1.0", "+1", "01", "%201", "0x1", "-0", "18446744073709551617"})
    checkError(s.api.get("/api/studies/" + id + "/runs/" + std::string(run)), 404, "run");
}

}  // namespace rover::test

namespace rover::test {

TEST_CASE("studies API: a study's name is versioned: rename, stale 412, none 428, hostile names, its event") {
  TempDir tmp;
  std::string id;
  {
    StudyServer s(tmp.str("data"));
    const HttpResult launched = s.api.postJson("/api/studies", tinySpec(2));
    REQUIRE(launched.status == 202);
    id = launched.json()["id"];
    CHECK(launched.json()["version"] == 1);
    const std::string target = "/api/studies/" + id;
    CHECK(s.api.get(target).headers["ETag"] == "\"v1\"");
    EventClient watcher(s.api.port(), "/api/events");
    REQUIRE(!watcher.nextOf("ready").is_null());

    const auto patch = [&](const json& body, const std::map<std::string, std::string>& headers) {
      return request(s.api.port(), "PATCH", target, body.dump(), "application/json", headers);
    };
    const std::map<std::string, std::string> v1{{"If-Match", "\"v1\""}};
    checkError(patch({{"name", "slopes"}}, {}), 428, "precondition_required", "If-Match");
    for (const json& bad : {json{{"name", ""}}, json{{"name", " "}}, json{{"name", std::string(201, 'a')}},
                            json{{"name", std::string("a\0b", 3)}}, json{{"name", "a\x1b[2J"}}, json{{"name", nullptr}}})
      checkError(patch(bad, v1), 400, "invalid_field", "name");
    checkError(patch({{"name", "x"}, {"spec", json::object()}}, v1), 400, "unknown_field", "spec");

    const HttpResult ok = patch({{"name", "slopes"}}, v1);
    REQUIRE(ok.status == 200);
    CHECK(ok.json()["name"] == "slopes");
    CHECK(ok.json()["version"] == 2);
    CHECK(ok.headers.at("ETag") == "\"v2\"");
    // Its event: changed study, the new version (no map).
    json e;
    for (json m = watcher.nextOf("events"); !m.is_null(); m = watcher.nextOf("events")) {
      for (const json& ev : m["events"])
        if (ev["object"] == "study" && ev["kind"] == "changed" && ev["version"] == 2) e = ev;
      if (!e.is_null()) break;
    }
    REQUIRE(!e.is_null());
    CHECK(e["id"] == id);
    CHECK(e["map"] == "");

    const HttpResult stale = patch({{"name", "mine"}, {"version", 1}}, {});
    checkError(stale, 412, "version_conflict", "If-Match");
    CHECK(stale.json()["error"]["current"]["name"] == "slopes");
    CHECK(stale.json()["error"]["current"]["version"] == 2);
    CHECK(s.api.get("/api/studies").json()[0]["name"] == "slopes");
    checkError(request(s.api.port(), "PATCH", "/api/studies/nope", json{{"name", "x"}}.dump(), "application/json", v1),
               404, "not_found", "id");
    // The study ends with its new name (its end writes its state after the rename, not over it).
    CHECK(s.waitEnded(id)["name"] == "slopes");
  }
  // Kept across a restart, with its version.
  StudyServer again(tmp.str("data"));
  const json back = again.study(id);
  CHECK(back["name"] == "slopes");
  CHECK(back["version"] == 2);
}

}  // namespace rover::test
