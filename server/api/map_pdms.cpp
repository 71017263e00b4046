#include "server/api/map_catalog.hpp"

// MapCatalog's PDMs: made from Gaussian components or a raster upload (read in the import jail),
// stored in the data dir charged to their map, and their mass on the map's grid kept in memory.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "server/api/map_files.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/pdm_json.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

std::string MapCatalog::pdmFile(const std::string& pdmId) const {
  return (fs::path(dir_.pdmDir(pdmId)) / "pdm.tif").string();
}

store::PdmRecord MapCatalog::createPdm(const std::string& mapId, const std::string& name,
                                       const std::vector<pdm::Gaussian>& components,
                                       const nlohmann::json& meta, const std::string& by) {
  const MapHeader map = header(mapId);  // the map is not loaded: its header and cells with data
  dir_.budget().requireRoom(store::DiskUse::Pdm, mapId, "body");
  // Discretised now to refuse components that put no mass on the map (400), as every later use
  // would; what is stored is the components (the mass is kept in memory for a while).
  Raster<float> mass;
  try {
    mass = pdm::discretise(components, map.geometry, validCells(mapId, map.geometry));
  } catch (const Error& e) {
    throw ApiError(400, "invalid_parameter", e.what(), e.field());
  }
  mass.geo = map.geo;
  const std::string stored = rover::json::toStoredJson(components).dump();
  const store::PdmRecord rec =
      storePdm(mapId, name.empty() ? "PDM " + store::nowIso() : name, meta, [&](const std::string& staging) {
        store::DataDir::writeFileAtomic((fs::path(staging) / "components.json").string(), stored);
      }, by);
  keepMass(rec.id + pdmVersionTag(rec.version), std::make_shared<const Raster<float>>(std::move(mass)));  // a mission often follows
  keepPyramid(mapId, rec.id, "");
  return rec;
}

store::PdmRecord MapCatalog::storePdm(const std::string& mapId, const std::string& name, const nlohmann::json& meta,
                                      const std::function<void(const std::string&)>& write, const std::string& by) {
  // Files first, then the row, as for maps.
  const std::string staging = dir_.stagingDir();
  try {
    write(staging);
    store::PdmRecord rec;
    rec.id = store::DataDir::newId();
    rec.mapId = mapId;
    rec.name = name;
    rec.createdAt = store::nowIso();
    rec.meta = meta;
    dir_.commitDir(staging, dir_.pdmDir(rec.id), store::DiskCharge{store::DiskUse::Pdm, mapId, "body"});
    db_.insertPdm(rec, by);
    return rec;
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
}

store::PdmRecord MapCatalog::createPdmFromRaster(const std::string& mapId, const std::string& name,
                                                 const std::string& rasterPath, const std::string& by) {
  auto map = get(mapId);
  const GridGeometry& g = map->dem.geometry();
  maps::LoadOptions o;
  o.maxCells = maxCells_;
  const auto& gt = map->dem.z.geo.geotransform;
  if (map->dem.z.geo.valid && !map->record.meta.value("geographic", false))
    o.crop = std::array<double, 4>{gt[0], gt[3] + g.rows * gt[5], g.cols * gt[1], -g.rows * gt[5]};
  // The raster is read in a folder of its own, so that it can read nothing else, by the import
  // jail (server/jail/).
  const std::string staging = dir_.stagingDir();
  const std::string stagedName = "pdm-raster" + fs::path(rasterPath).extension().string();
  maps::LoadedDem w;
  try {
    fs::rename(rasterPath, fs::path(staging) / stagedName);
    jail::ImportRequest req;
    req.kind = "pdm";
    req.sources = {stagedName};
    req.load = o;
    std::string shown;
    w = importJailed(staging, req, shown);
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
  store::DataDir::removeTree(staging);
  if (w.dem.geometry().rows != g.rows || w.dem.geometry().cols != g.cols)
    throw ApiError(400, "invalid_pdm",
                   "the PDM raster does not cover the map on its grid (" + std::to_string(w.dem.geometry().rows) +
                       " x " + std::to_string(w.dem.geometry().cols) + " cells, the map has " +
                       std::to_string(g.rows) + " x " + std::to_string(g.cols) + ")",
                   "file");
  Raster<float> mass;
  try {
    mass = pdm::normaliseWeights(w.dem.z, map->valid);
  } catch (const Error& e) {
    throw ApiError(400, "invalid_pdm", e.what(), "file");
  }
  mass.geo = map->dem.z.geo;
  const store::PdmRecord rec =
      storePdm(mapId, name.empty() ? "raster PDM" : name, {{"kind", "raster"}}, [&](const std::string& staging) {
        storingGeoTiff([&] { maps::writeGeoTiff((fs::path(staging) / "pdm.tif").string(), mass); });
      }, by);
  keepMass(rec.id + pdmVersionTag(rec.version), std::make_shared<const Raster<float>>(std::move(mass)));
  keepPyramid(mapId, rec.id, "");
  return rec;
}

std::string MapCatalog::pdmVersionTag(long long version) {
  return version > 1 ? "-v" + std::to_string(version) : std::string();
}

store::Cas MapCatalog::changePdm(const store::PdmRecord& current, const std::string& name,
                                 const std::optional<std::vector<pdm::Gaussian>>& components, long long expected,
                                 const std::string& by, store::PdmRecord& out) {
  out = current;
  out.name = name;
  std::shared_ptr<const Raster<float>> mass;
  std::string stored;
  if (components) {
    const MapHeader map = header(current.mapId);
    Raster<float> m;
    try {
      m = pdm::discretise(*components, map.geometry, validCells(current.mapId, map.geometry));
    } catch (const Error& e) {
      throw ApiError(400, "invalid_parameter", e.what(), e.field().empty() ? "components" : e.field());
    }
    m.geo = map.geo;
    mass = std::make_shared<const Raster<float>>(std::move(m));
    stored = rover::json::toStoredJson(*components).dump();
    // An edited random PDM is a Gaussian one from now on (its seed no longer makes it).
    out.meta = {{"kind", "gaussians"}, {"components", rover::json::toJson(*components)["components"]}};
  }
  const nlohmann::json body{{"name", out.name}, {"meta", out.meta}};
  const std::string file = (fs::path(dir_.pdmDir(current.id)) / "components.json").string();
  store::Cas done;
  try {
    done = db_.updatePdm(out, expected, body, by, [&] {
      if (components) store::DataDir::writeFileAtomic(file, stored);
    });
  } catch (...) {
    // The row was rolled back (a full disk): the file goes back to the components it names.
    if (components && current.meta.contains("components")) {
      try {
        const auto old = rover::json::gaussiansFromJson({{"components", current.meta["components"]}});
        store::DataDir::writeFileAtomic(file, rover::json::toStoredJson(old).dump());
      } catch (...) {
      }
    }
    throw;
  }
  if (done == store::Cas::Done) {
    out.version = expected + 1;
    forgetPdm(current.mapId, current.id, pdmVersionTag(out.version));  // the old version's files
    if (mass) {
      keepMass(current.id + pdmVersionTag(out.version), mass);
      keepPyramid(current.mapId, current.id, pdmVersionTag(out.version));
    }  // (a rename's pyramid, the same mass under the new version, is made by its first tile)
  }
  return done;
}

void MapCatalog::forgetPdm(const std::string& mapId, const std::string& pdmId,
                           const std::optional<std::string>& keepVersionTag) {
  // A name of this PDM's: "pdm-ID" or "t1-pdm-ID", then its version tag ("-vN", none for the
  // first), then "-..." or ".ext". Ids are fixed-length hex, so no other PDM's name matches.
  auto versionOf = [&](const std::string& name) -> std::optional<std::string> {
    for (const std::string& head : {"pdm-" + pdmId, std::string(kTileVersion) + "-pdm-" + pdmId}) {
      if (name.rfind(head, 0) != 0 || name.size() == head.size()) continue;
      std::string rest = name.substr(head.size());
      if (rest[0] == '.') return std::string();
      if (rest.rfind("-v", 0) != 0) return rest[0] == '-' ? std::optional<std::string>(std::string()) : std::nullopt;
      const std::size_t end = rest.find_first_not_of("0123456789", 2);
      if (end == 2) return std::string();  // "-v" not followed by digits: not a tag
      return rest.substr(0, end);
    }
    return std::nullopt;
  };
  layers_.discardUnder((fs::path(dir_.mapDir(mapId)) / "layers").string(), [&](const std::string& name) {
    const auto v = versionOf(name);
    return v && (!keepVersionTag || *v != *keepVersionTag);
  });
  std::lock_guard lock(mutex_);
  massCache_.remove_if([&](const auto& e) {
    if (e.first.rfind(pdmId, 0) != 0) return false;
    const std::string tag = e.first.substr(pdmId.size());
    return !keepVersionTag || tag != *keepVersionTag;
  });
}

void MapCatalog::keepMass(const std::string& key, std::shared_ptr<const Raster<float>> mass) {
  std::lock_guard lock(mutex_);
  massCache_.remove_if([&](const auto& e) { return e.first == key; });
  massCache_.emplace_front(key, std::move(mass));
  std::int64_t cells = 0;
  for (auto it = massCache_.begin(); it != massCache_.end();) {
    cells += it->second->geometry.cellCount();
    // The newest is kept whatever its size; older ones while they fit.
    if (it != massCache_.begin() && cells > kMassCacheCells) it = massCache_.erase(it);
    else ++it;
  }
}

std::shared_ptr<const Raster<float>> MapCatalog::pdmMass(const std::string& pdmId) {
  const auto rec = db_.getPdm(pdmId);
  if (!rec) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdmId) + "'", "pdm");
  return pdmMassOf(*rec);
}

std::shared_ptr<const Raster<float>> MapCatalog::pdmMassOf(const store::PdmRecord& rec) {
  const std::string key = rec.id + pdmVersionTag(rec.version);
  {
    std::lock_guard lock(mutex_);
    for (auto it = massCache_.begin(); it != massCache_.end(); ++it)
      if (it->first == key) {
        massCache_.splice(massCache_.begin(), massCache_, it);
        return massCache_.front().second;
      }
  }
  std::shared_ptr<const Raster<float>> mass;
  std::error_code ec;
  if (fs::exists(pdmFile(rec.id), ec)) {
    mass = std::make_shared<const Raster<float>>(maps::loadDem(pdmFile(rec.id)).dem.z);  // raster, or older
  } else {
    std::vector<pdm::Gaussian> components;
    if (rec.meta.contains("components")) {
      components = rover::json::gaussiansFromJson({{"components", rec.meta["components"]}});
    } else {
      std::ifstream in(fs::path(dir_.pdmDir(rec.id)) / "components.json");
      if (!in) throw std::runtime_error("PDM " + rec.id + ": neither pdm.tif nor components.json is stored");
      components = rover::json::gaussiansFromStoredJson(nlohmann::json::parse(in));
    }
    const MapHeader map = header(rec.mapId);  // the loaded map's, or the stored DEM's header
    Raster<float> m = pdm::discretise(components, map.geometry, validCells(rec.mapId, map.geometry));
    m.geo = map.geo;
    mass = std::make_shared<const Raster<float>>(std::move(m));
  }
  keepMass(key, mass);
  return mass;
}

std::vector<std::uint8_t> MapCatalog::validCells(const std::string& mapId, const GridGeometry& g) {
  {
    std::lock_guard lock(mutex_);
    for (const auto& m : cache_)
      if (m->record.id == mapId) return m->valid;
  }
  std::vector<std::uint8_t> valid(static_cast<std::size_t>(g.cellCount()));
  for (int r0 = 0; r0 < g.rows; r0 += kValidBandRows) {
    const int rows = std::min(kValidBandRows, g.rows - r0);
    const terrain::Dem band = readElevation(dir_.mapDir(mapId), [&](const std::string& stored) {
      try {
        return maps::loadDemWindow(stored, r0, 0, rows, g.cols).dem;
      } catch (const Error& e) {
        throw std::runtime_error(e.what());  // the stored file is the server's: 500, its path in the log only
      }
    });
    const float* z = band.z.values.data();
    std::uint8_t* out = valid.data() + std::size_t(r0) * g.cols;
    for (std::size_t i = 0, n = std::size_t(rows) * g.cols; i < n; ++i) out[i] = !std::isnan(z[i]);
  }
  return valid;
}

void MapCatalog::keepPyramid(const std::string& mapId, const std::string& pdmId, const std::string& versionTag) {
  try {
    pdmPyramidFile(mapId, pdmId, versionTag);
  } catch (const std::exception&) {
    // The PDM is stored; its pyramid is a cache file that its first tile makes again (and whose
    // failure, a full disk, that tile then reports).
  }
}

std::string MapCatalog::pdmPyramidFile(const std::string& mapId, const std::string& pdmId,
                                       const std::string& versionTag) {
  const fs::path dir = fs::path(dir_.mapDir(mapId)) / "layers";
  return layers_.get((dir / ("pdm-" + pdmId + versionTag + "-mass.tif")).string(), [&](const std::string& path) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    // The mass of the version the file names: a tile that raced an edit asks again.
    const auto rec = db_.getPdm(pdmId);
    if (!rec) throw ApiError(404, "not_found", "no PDM '" + rover::json::shown(pdmId) + "'", "pdm");
    if (pdmVersionTag(rec->version) != versionTag)
      throw ApiError(409, "conflict", "the PDM was edited while this picture was made: ask again", "pdm");
    const auto mass = pdmMassOf(*rec);
    // The ramp of the whole mass, once per version: what every tile of the version is drawn with.
    const maps::ColourRange range = maps::colourRange(maps::RenderLayer::Pdm, *mass);
    storingGeoTiff([&] { maps::writeMassCog(path, *mass, range); });
  });
}

}  // namespace rover::api
