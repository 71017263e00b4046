#pragma once
// What the server and an import worker (server/jail/import_jail.hpp) say to each other, as files
// in the worker's OUT folder:
//   request.json  the server's order: which files, how to read them (written before the start)
//   result.json   the grid's shape, cell sizes, georeferencing and what the file was
//   grid.f32      the heights, rows × cols little-endian float32, NaN for nodata
//   error.json    instead of a result: the answer for the client {status, code, message, field}
// The server trusts none of it: the worker parsed a hostile file and may be its puppet. The reader
// checks sizes against the budget, the georeferencing against maps::georefProblem, cell sizes, and
// recomputes every figure it reports (min/max height, nodata count) from the grid itself; it never
// hands the output to GDAL.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "maps/dem_io.hpp"

namespace rover::jail {

struct ImportRequest {
  std::string kind = "dem";          // dem: a map upload (pick the raster among the files); pdm: one raster
  std::vector<std::string> sources;  // file names in IN
  maps::LoadOptions load;            // cell size, crop, vertical scale, resampling, maxCells (upload unset)
  bool allowHdf5 = false;            // netCDF-4/HDF5 files: only when the worker cannot reach other files
};

void writeImportRequest(const std::string& outDir, const ImportRequest& request);
ImportRequest readImportRequest(const std::string& outDir);  // throws std::runtime_error

struct WorkerError {
  int status = 400;
  std::string code, message, field;
};

void writeWorkerError(const std::string& outDir, const WorkerError& error);
// The worker's error, bounded and cleaned (status 400 or 413, a code of [a-z_], no absolute
// paths in the message); nullopt when there is none or it does not read.
std::optional<WorkerError> readWorkerError(const std::string& outDir);

// `rasterName`: the file the map was read from, as the client named it.
void writeWorkerResult(const std::string& outDir, const maps::LoadedDem& dem, const std::string& rasterName);

struct WorkerResult {
  maps::LoadedDem dem;
  std::string rasterName;
};
// Throws std::runtime_error (the reason, for the server log) when the output is missing, malformed
// or over `maxCells`, or rover::Error (the georeferencing's field) when its georeferencing or cell
// sizes are out of range.
WorkerResult readWorkerResult(const std::string& outDir, std::int64_t maxCells);

// readWorkerResult in two steps, so the server never holds the grid (issue 24: a map import holds
// no full-size float copy): the header (every check of readWorkerResult but the values'; the
// raster has its geometry and georeferencing, no values), then the values in chunks of
// `rowsPerChunk` rows, each checked (no infinity) before `each(firstRow, rows, values)` sees it, the
// record's figures (min/max height, nodata count) set in `info` at the end. Each throws as
// readWorkerResult does; a chunk seen before a throw must be forgotten by the caller.
WorkerResult readWorkerHeader(const std::string& outDir, std::int64_t maxCells);
void readWorkerGrid(const std::string& outDir, const GridGeometry& g, maps::DemInfo& info, int rowsPerChunk,
                    const std::function<void(int, int, const float*)>& each);

}  // namespace rover::jail
