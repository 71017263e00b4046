#pragma once
// Where the server's studies live (StudyManager): DATA/studies/ID/ holds spec.json (the study
// document as accepted), state.json (status, times, message: rewritten atomically at each
// change), study.sqlite (the engine's study database), summary.json (an ended study's summary),
// runs.csv and benchmark.db (the last downloads) and, with a launcher, launcher.log. Never a client-chosen path:
// the id is the server's (DataDir::newId). Each study's folder is charged to the disk budget.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/store/data_dir.hpp"
#include "server/studies/study_state.hpp"

namespace rover::studies {

class StudyStore {
 public:
  explicit StudyStore(store::DataDir& dir);  // creates DATA/studies

  std::string folder(const std::string& id) const;
  std::string file(const std::string& id, const std::string& name) const;  // a file of its folder
  // Every stored study, oldest first; a folder without a readable state (a crash between mkdir
  // and the first write) is removed.
  std::vector<StudyState> load() const;
  // A new study's folder with its spec and first state; nothing is left behind when it fails.
  void create(const StudyState& s, const nlohmann::json& spec) const;
  void saveState(const StudyState& s) const;  // best effort on a full disk (logged)
  void writeState(const StudyState& s) const;  // the same, throwing (StorageFull) when it cannot
  nlohmann::json specJson(const std::string& id) const;
  std::string databasePath(const std::string& id) const;  // empty when there is none yet
  // summary.json, else the database's summary; null when it holds no run yet.
  nlohmann::json storedSummary(const std::string& id) const;
  bool hasSavedSummary(const std::string& id) const;
  void saveSummary(const std::string& id, const nlohmann::json& summary) const;  // throws on a full disk
  // runs.csv written (streamed) into the study's folder; returns its path.
  std::string runsCsvFile(const std::string& id) const;
  // benchmark.db (the study as an OMPL benchmark database) written into the study's folder; its
  // path. Empty when the study has no database yet.
  std::string benchmarkDbFile(const std::string& id) const;
  void remove(const std::string& id) const;  // the folder and its budget entry

  // The disk budget: 507 when it is full; charge throws store::OverBudget past it (a stat of the
  // few files in the folder: cheap enough at every commit); record takes what an ended study holds.
  void requireRoom() const;
  void chargeDisk(const std::string& id) const;
  void recordDisk(const std::string& id) const;

 private:
  store::DataDir& dir_;
};

}  // namespace rover::studies
