#pragma once
// DEM files in and layers out, through GDAL (DESIGN.md: maps/). Any raster GDAL reads — GeoTIFF,
// PDS3 .IMG+.LBL, ISIS3 .cub, PDS4, netCDF, ENVI, ASCII grid… — band 1, with the file's
// scale/offset applied, nodata respected (NaN in the result), geotransform and CRS kept, rows
// normalised to north-up, and cell sizes in metres even for geographic CRSs (from the CRS's own
// ellipsoid or sphere). Optional crop and resampling run through GDAL's warper.
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/terrain/dem.hpp"

namespace rover::maps {

class UploadSandbox;

struct LoadOptions {
  double cellSize = 0;  // metres; 0 = the file's own grid
  // Window in the file's CRS units: lower-left X0, Y0, width W, height H.
  std::optional<std::array<double, 4>> crop;
  // Or a window in pixels: first column, first row (from the upper-left corner), width, height
  // (gdal_translate -srcwin); converted to the CRS window through the geotransform.
  std::optional<std::array<double, 4>> cropPixels;
  double verticalScale = 1.0;                // multiplies heights after the file's scale/offset
  // metres added after verticalScale: radii to heights (−1 737 400 for a lunar file of radii),
  // or another datum                                                       [vertical_offset]
  double verticalOffset = 0.0;
  std::int64_t maxCells = 200'000'000;       // refused before anything is allocated
  std::string resampling = "auto";           // auto | near | average | bilinear | cubic
  // Set for a user's file (an upload): opened through openUpload() under this sandbox, which
  // must be live on the calling thread for the whole call; its own grid may hold at most
  // 4 × maxCells cells; messages name files as uploaded and carry no GDAL internals.
  const UploadSandbox* upload = nullptr;
};

struct DemInfo {
  std::string path;
  std::string driver;        // GDAL short name, e.g. GTiff, PDS, ISIS3
  int sourceCols = 0, sourceRows = 0;
  std::string crsName;       // "" when the file has no CRS
  bool geographic = false;   // pixel size in degrees
  bool georeferenced = false;
  double scale = 1.0, offset = 0.0;
  std::optional<double> nodata;
  std::int64_t nodataCells = 0;  // in the loaded grid (NaN in the file counts too)
  double minHeight = 0, maxHeight = 0;
  std::string resampling;    // what the warper used, "" when the grid was read as is
};

struct LoadedDem {
  terrain::Dem dem;
  DemInfo info;
};

// Throws rover::Error (InvalidInput, field "file") with a message "PATH: reason" for a missing,
// empty, truncated ("truncated or corrupt GeoTIFF") or non-raster file, a PDS3 .IMG without its
// label, an upload refused by the sandbox (a VRT, a file outside the upload), an over-budget size
// (field "max_cells"), all-nodata, infinite values, a crop outside the raster (field "crop" or
// "crop_px") or a
// cell size the map cannot hold twice (field "cell"). PATH may be a /vsizip/ or /vsitar/ member.
LoadedDem loadDem(const std::string& path, const LoadOptions& options = {});

// A north-up raster's grid from its header alone (no cell is read): rows, columns and cell sizes in
// metres as loadDem gives them for the file read as it is, and its georeferencing. What a server
// needs to check a mission area against a stored map without loading the map.
struct DemHeader {
  GridGeometry geometry;
  std::vector<double> rowCellWidth;  // a geographic map's east-west cell width per row (else empty)
  GeoReference geo;
  DemInfo info;  // minHeight, maxHeight and nodataCells are not known (0)
};
DemHeader readDemHeader(const std::string& path);

// Band 1's cells rows × cols from (row0, col0) (row 0 north) of a north-up raster read as it is —
// a mission area's planning window (core/planning/mission_area.hpp) — with one GDAL RasterIO
// window: only the blocks it touches are read, so a 600² window of a 49 M-cell map costs the
// window, not the map. Heights as loadDem reads them (scale, offset, nodata → NaN); the cell sizes
// are the whole raster's (loadDem's), so a position in the window plus the window's origin is the
// map's; the geotransform is the window's. Throws rover::Error like loadDem, field "area" for a
// window off the raster or a rotated or south-up raster. Memory: the window's floats only.
LoadedDem loadDemWindow(const std::string& path, int row0, int col0, int rows, int cols,
                        double verticalScale = 1.0);

// A GeoTIFF write failed because the disk (or the file size limit) is full. The message names
// only the file name, never its folder; the server answers it 507 (store::StorageFull).
class DiskFull : public std::runtime_error {
 public:
  explicit DiskFull(const std::string& fileName)
      : std::runtime_error("cannot write " + fileName + ": the disk is full"), fileName_(fileName) {}
  const std::string& fileName() const { return fileName_; }

 private:
  std::string fileName_;
};

// GeoTIFF writers, atomic (temporary file + rename). Float layers: NaN written as nodata -9999.
// Classes: uint8 with a colour table and category names (terrain::TerrainClass), nodata = 3.
// A full disk throws DiskFull and leaves no file behind.
void writeGeoTiff(const std::string& path, const Raster<float>& layer);
// writeGeoTiff's file for a float layer of `g`'s shape that is never whole in memory (issue 24: a
// big map's slope): `next(out)` puts the next rows, in order, into `out` (room for `bandRows` ×
// g.cols floats, NaN for nodata) and returns how many (1..bandRows); it is called until g.rows
// rows are in. Each finished row of the file's 256² tiles is compressed and written at once, so
// the writer holds `out` and one row of tiles. What `next` throws removes the file and propagates.
void writeGeoTiffInBands(const std::string& path, const GridGeometry& g, const GeoReference& geo, int bandRows,
                         const std::function<int(float* out)>& next);
void writeClassesGeoTiff(const std::string& path, const Raster<std::uint8_t>& classes);

}  // namespace rover::maps
