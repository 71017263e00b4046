#include "server/api/map_files.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/dem_io.hpp"
#include "maps/grid_file.hpp"
#include "maps/layer_bands.hpp"
#include "maps/render.hpp"
#include "server/api/map_catalog.hpp"
#include "server/store/data_dir.hpp"

namespace rover::api {

// GeoTIFF writes into the data dir: a full disk is the disk's fault, answered 507 like the .f32
// and .png layers (store::StorageFull), never 400 with the file's path.
void storingGeoTiff(const std::function<void()>& write) {
  try {
    write();
  } catch (const maps::DiskFull& e) {
    throw store::StorageFull("cannot write " + e.fileName());
  } catch (const Error& e) {
    // Any other failure to write into the data dir is the server's, not the request's: 500 with
    // the detail (which names the server's path) in the log only (routes.cpp's guard).
    if (e.field() == "out") throw std::runtime_error(e.what());
    throw;
  }
}

namespace {

// PNG overviews come in a fixed ladder of sizes: ?max= rounds up to the next rung, and a rung at
// least the map's own size is the full-size rendering, so a layer has at most 6 PNG files.
constexpr int kOverviewLadder[] = {256, 512, 1024, 2048, 4096};

}  // namespace

nlohmann::json rawStorage(int overviews) {
  return {{"elevation", "raw"}, {"codec", "none"}, {"overviews", overviews}};
}

nlohmann::json cogStorage(int overviews) {
  return {{"elevation", "cog"}, {"codec", "zstd"}, {"overviews", overviews}};
}

std::string elevationFile(const std::string& mapDir) {
  const std::filesystem::path dir(mapDir);
  std::error_code ec;
  if (std::filesystem::exists(dir / kDemFile, ec)) return (dir / kDemFile).string();
  if (std::filesystem::exists(dir / kRawDemDir / kRawDemVrt, ec)) return (dir / kRawDemDir / kRawDemVrt).string();
  return (dir / kDemFile).string();  // neither: the reader's error names the file a map keeps
}

bool storedAsPyramid(const store::MapRecord& r, const std::string& mapDir) {
  const auto it = r.meta.find("colour_range");
  std::error_code ec;
  return it != r.meta.end() && it->is_array() && it->size() == 2 && (*it)[0].is_number() && (*it)[1].is_number() &&
         std::filesystem::exists(std::filesystem::path(mapDir) / kClassFile, ec);
}

int overviewSide(int max, int nativeSide) {
  if (max <= 0) return 0;
  for (int rung : kOverviewLadder)
    if (max <= rung) return rung >= nativeSide ? 0 : rung;
  return 0;
}

// LAYER-N.png, pdm-ID-N.png with N off the ladder: never asked for again.
bool offLadderOverview(const std::string& file) {
  if (file.size() < 5 || file.compare(file.size() - 4, 4, ".png") != 0) return false;
  const std::string stem = file.substr(0, file.size() - 4);
  const auto dashes = std::count(stem.begin(), stem.end(), '-');
  if (dashes != (stem.rfind("pdm-", 0) == 0 ? 2 : 1)) return false;
  const std::string n = stem.substr(stem.rfind('-') + 1);
  if (n.empty() || n.size() > 6 || !std::all_of(n.begin(), n.end(), [](unsigned char c) { return std::isdigit(c); }))
    return false;
  return std::find(std::begin(kOverviewLadder), std::end(kOverviewLadder), std::stoi(n)) == std::end(kOverviewLadder);
}

void renderLayerFile(const MapData& map, const std::string& layer, const std::string& format, int side,
                     const Raster<float>* pdmMass, const std::string& path) {
  const terrain::Dem& dem = map.dem;
  Raster<float> values;
  if (layer == "elevation") values = dem.z;
  else if (layer == "hillshade") values = terrain::hillshade(dem);
  else if (layer == "slope") values = terrain::slopeHorn(dem);
  else if (layer == "pdm") values = *pdmMass;
  values.geo = dem.z.geo;
  if (format == "tif") {
    storingGeoTiff([&] {
      if (layer == "traversability") maps::writeClassesGeoTiff(path, map.traversability.classes);
      else maps::writeGeoTiff(path, values);
    });
  } else if (format == "f32") {
    std::string bytes;
    const int n = dem.geometry().cellCount();
    bytes.resize(4ull * n);
    for (int i = 0; i < n; ++i) {
      float v = layer == "traversability" ? static_cast<float>(map.traversability.classes.at(i)) : values.at(i);
      std::memcpy(&bytes[4ull * i], &v, 4);  // x86-64 and aarch64 are little-endian
    }
    store::DataDir::writeFileAtomic(path, bytes);
  } else {
    maps::RenderInput in;
    in.dem = &dem;
    Raster<float> shade;
    if (layer == "elevation" || layer == "hillshade") {
      shade = layer == "hillshade" ? values : terrain::hillshade(dem);
      in.hillshade = &shade;
    }
    if (layer == "slope") in.slopeDeg = &values;
    if (layer == "traversability") in.classes = &map.traversability.classes;
    if (layer == "pdm") in.pdm = &values;
    maps::RenderOptions ro;
    ro.maxSize = side;
    auto png = maps::encodePng(maps::renderLayer(maps::renderLayerFromName(layer), in, ro));
    store::DataDir::writeFileAtomic(path, std::string(png.begin(), png.end()));
  }
}

void streamLayerFile(const std::string& demPath, const maps::DemHeader& header, const std::string& layer,
                     const std::string& format, const std::string& path) {
  maps::LayerBands bands(demPath, header, maps::renderLayerFromName(layer));
  const GridGeometry& g = header.geometry;
  storingGeoTiff([&] {
    if (format == "tif") {
      maps::writeGeoTiffInBands(path, g, header.geo, maps::LayerBands::kBandRows,
                                [&](float* out) { return bands.next(out); });
      return;
    }
    // The f32 file: rows × cols little-endian floats as renderLayerFile writes them, through a
    // temporary file renamed into place (GridFileWriter: a full disk is DiskFull).
    const std::string tmp = path + ".tmp";
    try {
      maps::GridFileWriter out(tmp, g);
      std::vector<float> values(static_cast<std::size_t>(maps::LayerBands::kBandRows) * g.cols);
      while (const int n = bands.next(values.data()))
        out.append(values.data(), static_cast<std::size_t>(n) * g.cols);
      out.close();
      std::filesystem::rename(tmp, path);
    } catch (...) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw;
    }
  });
}

}  // namespace rover::api
