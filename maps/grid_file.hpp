#pragma once
// A map's heights as a plain file while it is imported (issue 24: an import holds no full-size
// float copy in memory): rows × cols little-endian float32, row 0 at the top, NaN for nodata,
// written by the server from the import worker's checked output (never the worker's own file,
// which a process the worker left behind could still change). Read back in bands of rows for the
// traversability classes, and through GDAL (a raw band, no copy) for the map's COG; the file's
// pages are the kernel's page cache, not the server's heap.
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/grid/geometry.hpp"
#include "core/terrain/layers.hpp"

namespace rover::maps {

// The server's own grid file failed to write or read (not the disk being full): the server's
// fault, never the upload's, so the import answers it 500 rather than 400.
class GridFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A grid file opened for positional reads and writes (pread/pwrite) by several threads at once,
// each call at its own offset: the overview levels' bands (maps/average_levels.hpp) and the rows
// of readGridRows. Throws GridFileError when the file does not open, read or write; DiskFull when
// a write lacks room (`fileBytes`: what the whole file will need, for the message's figure).
class GridFileHandle {
 public:
  GridFileHandle(const std::string& path, int openFlags);  // open(2)'s flags (O_RDONLY, O_WRONLY | O_CREAT …)
  ~GridFileHandle();
  GridFileHandle(const GridFileHandle&) = delete;
  GridFileHandle& operator=(const GridFileHandle&) = delete;

  void read(void* out, std::size_t bytes, std::int64_t at) const;  // all of it, or throws
  void write(const void* in, std::size_t bytes, std::int64_t at, double fileBytes) const;

 private:
  std::string path_;
  int fd_;
};

class GridFileWriter {
 public:
  // Creates (truncates) `path`; throws DiskFull when the disk lacks room for the grid, else
  // GridFileError.
  GridFileWriter(std::string path, const GridGeometry& g);
  ~GridFileWriter();
  GridFileWriter(const GridFileWriter&) = delete;
  GridFileWriter& operator=(const GridFileWriter&) = delete;
  void append(const float* values, std::size_t n);  // the next n cells in row order
  void flush();  // what was appended, readable by readGridRows (throws as the constructor)
  void close();                                       // flushes; throws as the constructor

 private:
  std::string path_;
  double bytes_;
  std::FILE* f_ = nullptr;
};

// The rows of a grid file while it is written, for a reader on another thread (issue 24: the
// import's classes are computed as the heights stream in, on the core the stream leaves idle):
// the writer publishes how many rows the file holds (after GridFileWriter::flush), a reader waits
// for the rows it needs; abort() (the stream failed) wakes it with GridFileError.
class GridRowsGate {
 public:
  void publish(int rows);
  void abort();
  void waitFor(int rows) const;  // throws GridFileError once aborted

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  int rows_ = 0;
  bool aborted_ = false;
};

// Cells [row0 · cols, (row0 + rows) · cols) of the grid file into `out`; throws std::runtime_error.
void readGridRows(const std::string& path, int cols, int row0, int rows, float* out);

// terrain::traversability of the grid file, computed in bands of `bandRows` rows each read with
// one row of halo above and below, on `threads` threads (0: every core; bands handed out in row
// order): the same classes and shares as on the whole grid (every cell's 8 neighbours are in its
// band) on any thread count, holding bandRows + 2 rows of heights a thread.
// With `gate`, each band waits for its rows (the file still being written).
// `eachBand(values, n)`, when given, sees each band's own cells (halo rows left out) in row order,
// one band at a time (the import digests the heights there, off the critical path).
terrain::Traversability traversabilityOfGridFile(const std::string& path, const GridGeometry& g,
                                                 const std::vector<double>& rowCellWidth, int bandRows,
                                                 const std::function<void(const float*, std::size_t)>& eachBand = {},
                                                 const GridRowsGate* gate = nullptr, unsigned threads = 1);

}  // namespace rover::maps
