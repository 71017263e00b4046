#pragma once
// A full-size layer of a stored map computed band by band, never the whole map in memory (issue
// 24: a HiRISE DTM of 50–300 M cells, whose slope or hillshade as a GeoTIFF the whole-map path
// would compute at about 15 bytes a cell). The stored DEM (its COG, or the raw VRT while the COG
// is written: maps/dem_pyramid.hpp) is read through one handle of its own, in chunks of whole
// rows of its blocks (each block decoded once, and dropped once read); a band's slope or
// hillshade is terrain::slopeHorn or terrain::hillshade (the code of the whole-map layers and
// tiles) on the band's heights plus the row above and the row below it, the 3×3 kernel's halo.
// So every value is the whole map's: a cell's Horn window lies in its band, the map's first and
// last rows are NaN as on the whole map (band edges inside the map are never handed out), and a
// geographic map's rows keep their own east-west cell widths.
// Memory, for C columns: the heights of the band, its halo and the chunk read ahead (at most
// kBandRows + 2 + 255 rows), a copy of the band with its halo and the layer's values on it
// (kBandRows + 2 rows each), 4 bytes a cell: about 4 KiB a column whatever the number of rows
// (measured on a 7000² map: 35 MiB more peak RSS, thread starts included, from its COG or its raw
// VRT alike). GDAL keeps none of the file: a COG's decoded blocks are dropped after each chunk,
// a raw grid's rows are read straight into the buffer.
#include <string>
#include <vector>

#include "core/terrain/dem.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/render.hpp"

namespace rover::maps {

class LayerBands {
 public:
  // Rows a band hands out: the height of the GeoTIFF's 256² tiles, so each band finishes a row of
  // them (maps::writeGeoTiffInBands writes it at once).
  static constexpr int kBandRows = 256;

  // `layer`: Elevation (the heights, NaN for nodata), Slope (degrees) or Hillshade (1..255, the
  // default sun), of the stored DEM at `demPath` whose header is `header` (readDemHeader). Throws
  // rover::Error (InvalidInput, "layer") for another layer, std::runtime_error when the file does
  // not open or is not the header's (the server's file, not a request's fault).
  LayerBands(const std::string& demPath, const DemHeader& header, RenderLayer layer);

  const GridGeometry& geometry() const { return header_.geometry; }
  // The next band's values, in row order, into `out` (kBandRows × cols floats); returns how many
  // rows (kBandRows, fewer for the last), 0 once every row was handed out. Throws
  // std::runtime_error when the file does not read.
  int next(float* out);

 private:
  // Reads whole chunks until the buffer holds rows up to `row` (exclusive).
  void readTo(int row);
  // Drops the buffer's rows above `row`.
  void dropAbove(int row);

  std::string path_;
  DemHeader header_;
  RenderLayer layer_;
  Dataset ds_;
  int chunk_ = 0;              // rows read at once: the file's block height
  bool hasNodata_ = false;
  float nodata_ = 0;
  std::vector<float> heights_;  // rows [lo_, hi_) of the map, row-major
  int lo_ = 0, hi_ = 0;
  int done_ = 0;                // rows handed out
};

}  // namespace rover::maps
