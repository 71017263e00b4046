#pragma once
// A DEM's identity for mission files (issue 13): the SHA-256 of what a planner sees of it, not of
// the file it came in. Two uploads of the same raster (same crop and cell) have the same digest
// whatever their container (GeoTIFF, PDS3, a zip), so a mission file names its ground exactly.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/terrain/dem.hpp"

namespace rover::maps {

// Lower-case hex SHA-256 of: "roverplan-dem-v1", rows and cols (int64 little-endian), the cell
// width and height (float64), the per-row cell widths when the map has them, then every height
// as float32 row by row from the top (NaN written as one canonical quiet NaN).
std::string demSha256(const terrain::Dem& dem);

// The same digest fed in pieces: the grid's shape and cell sizes first, then the heights in
// order (any number of calls to add), then hex() once. A map import digests the heights as they
// stream by, without the whole grid in memory.
class DemDigest {
 public:
  DemDigest(const GridGeometry& g, const std::vector<double>& rowCellWidth);
  ~DemDigest();
  DemDigest(const DemDigest&) = delete;
  DemDigest& operator=(const DemDigest&) = delete;
  void add(const float* heights, std::size_t n);
  std::string hex();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace rover::maps
