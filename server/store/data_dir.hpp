#pragma once
// The server's data directory: rasters and results as files, written atomically (temp + rename),
// so a crash never leaves a half-written file or folder visible (issue: server, storage).
//   DATA/roverplan.db     SQLite metadata (Database)
//   DATA/maps/ID/         one folder per map (source DEM, cached layers)
//   DATA/pdms/ID/         one folder per PDM (components, mass raster)
//   DATA/missions/ID/     one folder per mission (result.json, result.geojson, result.csv)
//   DATA/tmp/             uploads in flight and folders being built; emptied at start-up
#include <string>

namespace rover::store {

class DataDir {
 public:
  // Creates the layout if missing; throws std::runtime_error if the folder is not writable.
  explicit DataDir(std::string root);
  const std::string& root() const { return root_; }
  std::string databasePath() const;
  std::string mapDir(const std::string& id) const;
  std::string pdmDir(const std::string& id) const;
  std::string missionDir(const std::string& id) const;
  std::string tmpDir() const;

  // A new random id: 16 lowercase hex characters.
  static std::string newId();
  // A fresh empty folder under tmp/ to build something in before commitDir().
  std::string stagingDir() const;
  // Atomically moves a staged folder to its final place (rename); throws if the target exists.
  void commitDir(const std::string& staged, const std::string& finalDir) const;
  // Writes bytes to `path` atomically (temp file in the same folder, fsync, rename).
  static void writeFileAtomic(const std::string& path, const std::string& bytes);
  // Removes a folder and everything in it (no error if absent).
  static void removeTree(const std::string& path);
  // Empties tmp/ (start-up: whatever was in flight when the server died is discarded).
  void cleanTmp() const;

 private:
  std::string root_;
};

}  // namespace rover::store
