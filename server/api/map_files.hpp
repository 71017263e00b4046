#pragma once
// The files of a stored map besides its DEM (MapCatalog::layerFile): layer renderings as PNG
// (with a legend, on a ladder of overview sizes), GeoTIFF or raw float32; and how the catalog
// writes a GeoTIFF into the data dir.
#include <functional>
#include <string>

#include "core/grid/raster.hpp"
#include "core/terrain/body.hpp"
#include "maps/dem_io.hpp"
#include "server/store/database.hpp"

namespace rover::api {

struct MapData;

// A stored map's folder: the elevation (a COG since issue 24's pyramid; a tiled GeoTIFF without
// overviews before) and the class pyramid (maps/dem_pyramid.hpp; absent for a map stored before).
inline constexpr const char* kDemFile = "dem.tif";
inline constexpr const char* kClassFile = "classes.tif";
// A map whose COG is still being written (issue 24: a map is announced before its elevation is
// compressed) keeps its elevation raw in this folder: the server's float32 grid, its overview
// levels and dem.vrt over them (maps::writeRawDem), which every reader opens as it opens dem.tif.
// The folder goes once dem.tif is in place (MapCatalog's compressor).
inline constexpr const char* kRawDemDir = "dem~raw";  // "~": never an upload's name (safeName)
inline constexpr const char* kRawDemVrt = "dem.vrt";

// The record's meta.storage for a map whose elevation is raw (its COG being written) and once it
// is the COG: {"elevation": "raw" | "cog", "codec": "none" | "zstd", "overviews": N}.
nlohmann::json rawStorage(int overviews);
nlohmann::json cogStorage(int overviews);

// The map's elevation file, the one every reader opens: dem.tif when it is there, else the raw
// DEM's VRT (kRawDemDir/kRawDemVrt).
std::string elevationFile(const std::string& mapDir);
// `read(elevationFile(mapDir))`. A read of the raw VRT that fails because the COG replaced it
// meanwhile (its files removed under the reader) is done again from dem.tif, so a read racing
// the swap never fails. `read` must only read.
template <class Read>
auto readElevation(const std::string& mapDir, Read&& read) -> decltype(read(std::string())) {
  const std::string path = elevationFile(mapDir);
  try {
    return read(path);
  } catch (...) {
    if (path == elevationFile(mapDir)) throw;  // not the swap: the read's own failure
  }
  return read(elevationFile(mapDir));
}

// A map stored as its pyramid (issue 24): its class pyramid in `mapDir` and its elevation ramp in
// its record. Its tiles and overviews are read from the pyramid; a map stored before is loaded.
bool storedAsPyramid(const store::MapRecord& record, const std::string& mapDir);

// The longest side of the PNG overview for ?max= on a map whose longest side is `nativeSide`: the
// next rung of the ladder 256, 512, 1024, 2048, 4096; 0 (full size) for max 0 or a rung at least
// the map's own size.
int overviewSide(int max, int nativeSide);
// A PNG overview file named by a size off the ladder (written before the ladder existed): the
// layer cache drops such files.
bool offLadderOverview(const std::string& file);

// The map's body: declared at upload (its record's meta), else the body of its CRS.
terrain::Body mapBody(const store::MapRecord& record, const std::string& crsWkt);

// Runs `write`, a GeoTIFF (or streamed .f32) write into the data dir: a full disk throws
// store::StorageFull (507), any other failure to write there is the server's (std::runtime_error, 500).
void storingGeoTiff(const std::function<void()>& write);

// Renders `layer` (elevation|hillshade|slope|traversability|pdm) of `map` as `format`
// (png|tif|f32) into `path`; `side` > 0 for a PNG overview, `pdmMass` for the pdm layer.
void renderLayerFile(const MapData& map, const std::string& layer, const std::string& format, int side,
                     const Raster<float>* pdmMass, const std::string& path);

// renderLayerFile's tif or f32 of elevation, slope or hillshade, for a map too big to load whole
// (MapCatalog::layerFile): computed band by band from the stored DEM at `demPath`, whose header
// is `header`, by maps::LayerBands (the same values and georeferencing), and written as it goes;
// memory is a band of rows (maps/layer_bands.hpp), never the map. Atomic like renderLayerFile's.
void streamLayerFile(const std::string& demPath, const maps::DemHeader& header, const std::string& layer,
                     const std::string& format, const std::string& path);

}  // namespace rover::api
