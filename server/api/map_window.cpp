// MapCatalog's planning windows (issue 24, the mission area): a map's header, the DEM cells of a
// window and a PDM's mass there, each read without loading the whole map.
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/map_files.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

// A loader error about a stored file, in words that name the map, never the file the server keeps
// it in (a server path in a message is a leak).
[[noreturn]] void rethrowAboutMap(const Error& e, const std::string& stored, const std::string& field) {
  std::string msg = e.what();
  if (msg.rfind(stored, 0) == 0) msg = "the map" + msg.substr(stored.size());
  throw ApiError(400, "invalid_field", maps::withoutPaths(msg), field);
}

}  // namespace

MapHeader MapCatalog::header(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    for (const auto& m : cache_)
      if (m->record.id == id) return {m->dem.geometry(), m->dem.z.geo, m->body};
  }
  auto rec = db_.getMap(id);
  if (!rec) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  const maps::DemHeader h = readElevation(dir_.mapDir(id), [&](const std::string& stored) -> maps::DemHeader {
    try {
      return maps::readDemHeader(stored);
    } catch (const Error& e) {
      rethrowAboutMap(e, stored, "map");
    }
  });
  return {h.geometry, h.geo, mapBody(*rec, h.geo.crsWkt)};
}

std::shared_ptr<const terrain::Dem> MapCatalog::demWindow(const std::string& id, const PlanningWindow& w) {
  if (!db_.getMap(id)) throw ApiError(404, "not_found", "no map '" + rover::json::shown(id) + "'", "id");
  return readElevation(dir_.mapDir(id), [&](const std::string& stored) -> std::shared_ptr<const terrain::Dem> {
    try {
      return std::make_shared<const terrain::Dem>(
          maps::loadDemWindow(stored, w.row0, w.col0, w.grid.rows, w.grid.cols).dem);
    } catch (const Error& e) {
      rethrowAboutMap(e, stored, "area");
    }
  });
}

std::shared_ptr<const Raster<float>> MapCatalog::pdmMassIn(const std::string& pdmId, const PlanningWindow& w,
                                                           const terrain::Dem& windowDem,
                                                           const std::vector<std::uint8_t>& inArea) {
  const auto rec = db_.getPdm(pdmId);
  if (!rec) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdmId) + "'", "pdm");
  std::vector<std::uint8_t> valid = inArea;
  for (std::size_t i = 0; i < valid.size(); ++i) valid[i] = valid[i] && !std::isnan(windowDem.z.at(static_cast<int>(i)));
  const std::string raster = pdmFile(pdmId);
  Raster<float> mass;
  try {
    std::error_code ec;
    if (fs::exists(raster, ec)) {
      // A stored mass raster on the map's grid: its window, renormalised over the area.
      mass = pdm::normaliseWeights(maps::loadDemWindow(raster, w.row0, w.col0, w.grid.rows, w.grid.cols).dem.z, valid);
    } else {
      std::ifstream in(fs::path(dir_.pdmDir(pdmId)) / "components.json");
      if (!in) throw std::runtime_error("PDM " + pdmId + ": neither pdm.tif nor components.json is stored");
      const auto components = rover::json::gaussiansFromStoredJson(nlohmann::json::parse(in));
      const MapHeader map = header(rec->mapId);
      mass = pdm::discretiseOnWindow(components, map.geometry, w.grid, w.origin, valid);
    }
  } catch (const Error& e) {
    // The PDM's mass lies elsewhere on the map (or the stored raster does not read there).
    throw ApiError(400, "invalid_field",
                   "the PDM puts no probability in the mission area (" + maps::withoutPaths(e.what()) +
                       "): choose an area where it does, or another PDM",
                   "pdm");
  }
  mass.geo = windowDem.z.geo;
  return std::make_shared<const Raster<float>>(std::move(mass));
}

}  // namespace rover::api
