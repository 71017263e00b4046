#include "server/studies/study_store.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "server/store/database.hpp"
#include "server/store/disk_budget.hpp"
#include "server/studies/studies.hpp"
#include "server/studies/study_summary.hpp"

namespace rover::studies {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json readJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  return json::parse(in);
}

// state.json: the study object without its links.
std::string stateText(const StudyState& s) {
  json j = toJson(s);
  j.erase("links");
  return j.dump(1);
}

}  // namespace

StudyStore::StudyStore(store::DataDir& dir) : dir_(dir) { fs::create_directories(fs::path(dir_.root()) / "studies"); }

std::string StudyStore::folder(const std::string& id) const {
  return (fs::path(dir_.root()) / "studies" / id).string();
}

std::string StudyStore::file(const std::string& id, const std::string& name) const {
  return (fs::path(folder(id)) / name).string();
}

std::vector<StudyState> StudyStore::load() const {
  std::vector<StudyState> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir_.root()) / "studies", ec)) {
    if (!e.is_directory()) continue;
    try {
      const json j = readJsonFile((e.path() / "state.json").string());
      StudyState s;
      s.id = j.at("id").get<std::string>();
      if (s.id != e.path().filename().string()) continue;
      s.name = j.value("name", "");
      s.version = j.value("version", 1LL);  // a state written before renames: version 1
      // A name this server does not know counts as unfinished: queued again, as before.
      s.status = parseEnum<RunStatus>(j.value("status", "")).value_or(RunStatus::Queued);
      s.message = j.value("message", "");
      s.createdAt = j.value("created_at", "");
      s.startedAt = j.value("started_at", "");
      s.finishedAt = j.value("finished_at", "");
      s.done = j.value("runs_done", std::size_t{0});
      s.total = j.value("runs_total", std::size_t{0});
      found.push_back(std::move(s));
    } catch (const std::exception&) {
      // A folder without a readable state (a crash between mkdir and the first write): dropped.
      store::DataDir::removeTree(e.path().string());
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.createdAt < b.createdAt; });
  return found;
}

void StudyStore::create(const StudyState& s, const json& spec) const {
  const std::string dirPath = folder(s.id);
  fs::create_directories(dirPath);
  try {
    store::DataDir::writeFileAtomic((fs::path(dirPath) / "spec.json").string(), spec.dump(1));
    store::DataDir::writeFileAtomic((fs::path(dirPath) / "state.json").string(), stateText(s));
  } catch (...) {
    store::DataDir::removeTree(dirPath);
    throw;
  }
}

void StudyStore::writeState(const StudyState& s) const {
  store::DataDir::writeFileAtomic(file(s.id, "state.json"), stateText(s));
}

void StudyStore::saveState(const StudyState& s) const {
  try {
    store::DataDir::writeFileAtomic(file(s.id, "state.json"), stateText(s));
  } catch (const std::exception& e) {
    // A full disk: the state stays in memory; the next change writes it again.
    std::cerr << "roverplan: study " << s.id << ": cannot store its state: " << e.what() << "\n";
  }
}

json StudyStore::specJson(const std::string& id) const { return readJsonFile(file(id, "spec.json")); }

std::string StudyStore::databasePath(const std::string& id) const {
  const fs::path p = file(id, "study.sqlite");
  std::error_code ec;
  return fs::is_regular_file(p, ec) ? p.string() : std::string();
}

json StudyStore::storedSummary(const std::string& id) const {
  std::error_code ec;
  const fs::path saved = file(id, "summary.json");
  if (fs::is_regular_file(saved, ec)) {
    try {
      return readJsonFile(saved.string());
    } catch (const std::exception&) {
      // Unreadable (cut short by a full disk): the database still has every run.
    }
  }
  const std::string path = databasePath(id);
  if (path.empty()) return nullptr;
  StudyDb db = StudyDb::open(path);  // a second connection: WAL readers do not block the writer
  if (!db.hasSpec()) return nullptr;
  return toJson(db.summary());
}

bool StudyStore::hasSavedSummary(const std::string& id) const {
  std::error_code ec;
  return fs::exists(file(id, "summary.json"), ec);
}

void StudyStore::saveSummary(const std::string& id, const json& summary) const {
  store::DataDir::writeFileAtomic(file(id, "summary.json"), summary.dump());
}

std::string StudyStore::runsCsvFile(const std::string& id) const {
  // Streamed from the database into a file of the study's folder (temp + rename, so a download
  // in progress keeps its own copy): memory stays small however many runs the study has.
  const fs::path out = fs::path(folder(id)) / "runs.csv";
  const fs::path temp = fs::path(folder(id)) / ("runs.csv." + store::DataDir::newId());
  {
    std::ofstream f(temp, std::ios::binary);
    if (!f) throw std::runtime_error("cannot write " + temp.string());
    const std::string path = databasePath(id);
    if (!path.empty()) {
      StudyDb db = StudyDb::open(path);
      if (db.hasSpec()) db.runsCsv(f);
    }
    f.flush();
    if (!f) {
      std::error_code ec;
      fs::remove(temp, ec);
      throw store::StorageFull("the study's runs.csv");
    }
  }
  fs::rename(temp, out);
  return out.string();
}

std::string StudyStore::benchmarkDbFile(const std::string& id) const {
  const std::string path = databasePath(id);
  if (path.empty()) return {};
  StudyDb db = StudyDb::open(path);
  if (!db.hasSpec()) return {};
  // Temp + rename, as runs.csv: a download in progress keeps its own copy.
  const fs::path out = fs::path(folder(id)) / "benchmark.db";
  const fs::path temp = fs::path(folder(id)) / ("benchmark.db." + store::DataDir::newId());
  try {
    db.writeOmplBenchmark(temp.string());
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
  fs::rename(temp, out);
  return out.string();
}

void StudyStore::remove(const std::string& id) const { dir_.remove(folder(id)); }

void StudyStore::requireRoom() const {
  dir_.budget().requireRoom(store::DiskUse::Study, "");  // 507 when the disk budget is full
}

void StudyStore::chargeDisk(const std::string& id) const {
  dir_.budget().charge(folder(id), store::DiskUse::Study, "", store::bytesUnder(folder(id)));
}

void StudyStore::recordDisk(const std::string& id) const {
  dir_.budget().record(folder(id), store::DiskUse::Study, "", store::bytesUnder(folder(id)));
}

}  // namespace rover::studies
