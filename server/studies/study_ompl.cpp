// A study database written as an OMPL benchmark database (issue 28), so Planner Arena and OMPL's
// scripts/ompl_benchmark_statistics.py (-p, plots) read our studies as they read OMPL's.
//
// The tables and their columns are the ones that script creates (readBenchmarkLog) and OMPL's
// "benchmark database schema" documents (doc/markdown/benchmark.md):
//   experiments(id, name, totaltime, timelimit, memorylimit, runcount, version, hostname,
//               cpuinfo, date, seed, setup)          one per world of the study (OMPL's "problem")
//   plannerConfigs(id, name, settings)                one per planner point and team size
//   enums(name, value, description)                   "status": the planners' stop reasons
//   runs(id, experimentid, plannerid, <property> ...) one per run; properties as the script adds
//                                                     them, one typed column each (below)
//   progress(runid, time, <property> ...)             the run's sampled progress curve
// Our run properties: run_index, replicate, seed (INTEGER), time (REAL: the run's wall seconds, as
// OMPL's time), cpu_time (REAL), status (ENUM), then every metric (REAL), named as the script names
// properties (words joined by '_'; '@' -> "_at_", '%' -> "pct", anything else not a letter or
// digit -> '_'). Our planners progress over moves or metres, not seconds: progress.time holds the
// curve's abscissa, repeated under its own name ("moves", "distance_team"), beside the ordinate
// ("coverage", "probability"): a curve "Y_vs_X" gives the columns X and Y.
// No time or memory limit bounds a run (each ends by its own stop rule): both are 0.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <set>

#include "core/planning/outcomes.hpp"
#include "server/json/plan_json.hpp"
#include "server/store/sqlite_stmt.hpp"
#include "server/studies/study_db.hpp"
#include "server/studies/study_version.hpp"

namespace rover::studies {

using store::exec;
using store::Stmt;

namespace {

constexpr const char* kOmplSchema = R"sql(
CREATE TABLE experiments(
  id INTEGER PRIMARY KEY AUTOINCREMENT, name VARCHAR(512), totaltime REAL, timelimit REAL,
  memorylimit REAL, runcount INTEGER, version VARCHAR(128), hostname VARCHAR(1024), cpuinfo TEXT,
  date DATETIME, seed VARCHAR(24), setup TEXT);
CREATE TABLE plannerConfigs(
  id INTEGER PRIMARY KEY AUTOINCREMENT, name VARCHAR(512) NOT NULL, settings TEXT);
CREATE TABLE enums(
  name VARCHAR(512), value INTEGER, description TEXT, PRIMARY KEY (name, value));
CREATE TABLE runs(
  id INTEGER PRIMARY KEY AUTOINCREMENT, experimentid INTEGER, plannerid INTEGER,
  FOREIGN KEY (experimentid) REFERENCES experiments(id) ON DELETE CASCADE,
  FOREIGN KEY (plannerid) REFERENCES plannerConfigs(id) ON DELETE CASCADE);
CREATE TABLE progress(
  runid INTEGER, time REAL, PRIMARY KEY (runid, time),
  FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE);
)sql";

// The fixed properties of a run, before the metrics.
const std::vector<std::pair<std::string, std::string>> kRunProperties{
    {"run_index", "INTEGER"}, {"replicate", "INTEGER"}, {"seed", "INTEGER"},
    {"time", "REAL"},         {"cpu_time", "REAL"},     {"status", "ENUM"}};

// A property name as the script makes them: an SQL identifier a query can use unquoted.
std::string propertyName(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') out += c;
    else if (c == '@') out += "_at_";
    else if (c == '%') out += "pct";
    else out += '_';
  }
  if (out.empty() || std::isdigit(static_cast<unsigned char>(out[0]))) out.insert(0, "m_");
  return out;
}

// `name`, or name_2, name_3... when taken: each property its own column.
std::string unique(std::string name, std::set<std::string>& taken) {
  const std::string base = name;
  for (int i = 2; taken.count(name); ++i) name = base + "_" + std::to_string(i);
  taken.insert(name);
  return name;
}

std::string jsonText(const ParamValue& v) { return json::toJson(v).dump(); }

// OMPL's settings: the planner's common properties, "name = value" each, ';' after each.
std::string settingsOf(const Configuration& c) {
  std::string s = "planner = " + c.point.planner + ";rovers = " + std::to_string(c.rovers) + ";";
  for (const auto& [k, v] : c.point.params) s += k + " = " + jsonText(v) + ";";
  return s;
}

struct CurveColumns {
  std::string x, y;
};

// "coverage_vs_moves" -> moves, coverage.
CurveColumns curveColumns(const std::string& key) {
  const auto vs = key.find("_vs_");
  if (vs == std::string::npos) return {"x", propertyName(key)};
  return {propertyName(key.substr(vs + 4)), propertyName(key.substr(0, vs))};
}

}  // namespace

OmplCounts StudyDb::writeOmplBenchmark(const std::string& path) const {
  const StudySpec spec = parseStudySpec(specJson());
  std::string createdAt, version;
  {
    Stmt s(db_, "SELECT created_at, version FROM study WHERE id = 1");
    s.step();
    createdAt = s.text(0);
    version = s.text(1);
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  sqlite3* out = nullptr;
  if (sqlite3_open_v2(path.c_str(), &out, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    const std::string msg = out ? sqlite3_errmsg(out) : "out of memory";
    sqlite3_close(out);
    throw std::runtime_error("cannot write " + path + ": " + msg);
  }
  const std::unique_ptr<sqlite3, int (*)(sqlite3*)> guard(out, sqlite3_close);
  OmplCounts counts;
  exec(out, kOmplSchema);
  exec(out, "BEGIN");

  // enums: the stop reasons, valued by their place in the one table (core/planning/outcomes.hpp).
  const std::vector<std::string> reasons = enumNames<StopReason>();
  {
    Stmt e(out, "INSERT INTO enums(name, value, description) VALUES ('status', ?, ?)");
    for (std::size_t i = 0; i < reasons.size(); ++i, ++counts.enums) {
      e.bindInt(1, static_cast<long long>(i)).bind(2, reasons[i]).run();
      e.reset();
    }
  }

  // plannerConfigs: one per (name, settings), as the script shares a configuration between experiments.
  std::map<std::pair<std::string, std::string>, long long> plannerIds;
  std::vector<long long> plannerOf(spec.configurations.size());
  {
    Stmt p(out, "INSERT INTO plannerConfigs(name, settings) VALUES (?, ?)");
    for (const auto& c : spec.configurations) {
      std::string name = c.point.name == "default" ? c.point.planner : c.point.name;
      if (spec.rovers.size() > 1) name.append(" ").append(std::to_string(c.rovers)).append("r");
      const auto key = std::make_pair(name, settingsOf(c));
      auto it = plannerIds.find(key);
      if (it == plannerIds.end()) {
        p.bind(1, key.first).bind(2, key.second).run();
        p.reset();
        it = plannerIds.emplace(key, sqlite3_last_insert_rowid(out)).first;
        ++counts.plannerConfigs;
      }
      plannerOf[static_cast<std::size_t>(c.id)] = it->second;
    }
  }

  // runs: the fixed properties, then one REAL column per metric.
  std::set<std::string> taken{"id", "experimentid", "plannerid"};
  std::string cols = "experimentid, plannerid", marks = "?, ?";
  for (const auto& [name, type] : kRunProperties) {
    exec(out, ("ALTER TABLE runs ADD " + unique(name, taken) + " " + type).c_str());
    cols += ", " + name;
    marks += ", ?";
  }
  const std::vector<std::string> keys = metricKeys();
  std::string metricCols;
  for (const auto& k : keys) {
    const std::string name = unique(propertyName(k), taken);
    exec(out, ("ALTER TABLE runs ADD " + name + " REAL").c_str());
    cols += ", " + name;
    marks += ", ?";
    metricCols += ", " + metricColumnSql(k);
  }
  std::vector<double> worldSeconds(spec.worlds.size(), 0);
  std::vector<std::set<std::string>> worldHosts(spec.worlds.size());
  {
    Stmt in(db_, ("SELECT run_index, config_id, replicate, seed, status, wall_s, cpu_s, host" + metricCols +
                  " FROM runs ORDER BY run_index").c_str());
    Stmt ins(out, ("INSERT INTO runs(id, " + cols + ") VALUES (?, " + marks + ")").c_str());
    while (in.step()) {
      const auto configId = static_cast<std::size_t>(in.integer(1));
      if (configId >= spec.configurations.size()) throw std::runtime_error("run of an unknown configuration");
      const std::size_t world = spec.configurations[configId].world;
      worldSeconds[world] += in.real(5);
      if (!in.text(7).empty()) worldHosts[world].insert(in.text(7));
      // OMPL's ids count from 1: run_index + 1.
      ins.bindInt(1, in.integer(0) + 1).bindInt(2, static_cast<long long>(world) + 1).bindInt(3, plannerOf[configId]);
      ins.bindInt(4, in.integer(0)).bindInt(5, in.integer(2)).bindInt(6, in.integer(3));
      ins.bindReal(7, in.real(5)).bindReal(8, in.real(6));
      const auto reason = std::find(reasons.begin(), reasons.end(), in.text(4));
      if (reason == reasons.end()) ins.bindReal(9, std::numeric_limits<double>::quiet_NaN());
      else ins.bindInt(9, reason - reasons.begin());
      for (std::size_t k = 0; k < keys.size(); ++k) {
        const int col = static_cast<int>(k) + 8;
        ins.bindReal(static_cast<int>(k) + 10, in.isNull(col) ? std::numeric_limits<double>::quiet_NaN() : in.real(col));
      }
      ins.run();
      ins.reset();
    }
  }

  // experiments: one per world, with ids 1.. in the spec's order.
  {
    Stmt e(out, "INSERT INTO experiments(id, name, totaltime, timelimit, memorylimit, runcount, version, hostname, "
                "cpuinfo, date, seed, setup) VALUES (?, ?, ?, 0, 0, ?, ?, ?, NULL, ?, ?, ?)");
    for (std::size_t w = 0; w < spec.worlds.size(); ++w, ++counts.experiments) {
      std::string hosts;
      for (const auto& h : worldHosts[w]) {
        if (!hosts.empty()) hosts += ", ";
        hosts += h;
      }
      e.bindInt(1, static_cast<long long>(w) + 1);
      e.bind(2, spec.worlds.size() > 1 ? spec.name + " · " + spec.worlds[w].name : spec.name);
      e.bindReal(3, worldSeconds[w]).bindInt(4, spec.runs);
      // Planner Arena reads the version as its last word.
      e.bind(5, "roverplan " + version).bind(6, hosts).bind(7, createdAt);
      e.bind(8, std::to_string(spec.masterSeed)).bind(9, spec.json.dump(2)).run();
      e.reset();
    }
  }

  // progress: each stored curve's samples, its abscissa as time.
  {
    std::map<std::string, CurveColumns> columnsOf;
    std::set<std::string> progressTaken{"runid", "time"};
    Stmt c(db_, "SELECT run_index, curve, x, y FROM curves ORDER BY run_index, curve");
    while (c.step()) {
      const std::string key = c.text(1);
      auto it = columnsOf.find(key);
      if (it == columnsOf.end()) {
        CurveColumns cc = curveColumns(key);
        cc.x = unique(cc.x, progressTaken);
        cc.y = unique(cc.y, progressTaken);
        exec(out, ("ALTER TABLE progress ADD " + cc.x + " REAL").c_str());
        exec(out, ("ALTER TABLE progress ADD " + cc.y + " REAL").c_str());
        it = columnsOf.emplace(key, cc).first;
      }
      const nlohmann::json xs = nlohmann::json::parse(c.text(2)), ys = nlohmann::json::parse(c.text(3));
      Stmt p(out, ("INSERT INTO progress(runid, time, " + it->second.x + ", " + it->second.y +
                   ") VALUES (?, ?, ?, ?) ON CONFLICT(runid, time) DO UPDATE SET " + it->second.x + " = excluded." +
                   it->second.x + ", " + it->second.y + " = excluded." + it->second.y)
                      .c_str());
      const auto value = [](const nlohmann::json& v) {
        return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
      };
      for (std::size_t i = 0; i < xs.size() && i < ys.size(); ++i) {
        const double x = value(xs[i]);
        if (x != x) continue;  // no abscissa: no time to key the sample by
        p.bindInt(1, c.integer(0) + 1).bindReal(2, x).bindReal(3, x).bindReal(4, value(ys[i])).run();
        p.reset();
      }
    }
  }
  exec(out, "COMMIT");
  const auto rows = [&](const char* table) {
    Stmt n(out, (std::string("SELECT count(*) FROM ") + table).c_str());
    n.step();
    return static_cast<std::size_t>(n.integer(0));
  };
  counts.runs = rows("runs");
  counts.progress = rows("progress");
  return counts;
}

}  // namespace rover::studies
