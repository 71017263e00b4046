#include "maps/grid_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <condition_variable>
#include <mutex>
#include <cerrno>
#include <stdexcept>

#include "core/common/parallel.hpp"
#include "maps/dem_error.hpp"
#include "maps/dem_io.hpp"

namespace rover::maps {

namespace {

[[noreturn]] void failWrite(const std::string& path, int err, double bytes) {
  std::remove(path.c_str());
  if (lacksSpace(path, err, bytes)) throw DiskFull(path.substr(path.find_last_of('/') + 1));
  throw GridFileError("cannot write " + path);
}

}  // namespace

GridFileHandle::GridFileHandle(const std::string& path, int openFlags)
    : path_(path), fd_(::open(path.c_str(), openFlags | O_CLOEXEC, 0644)) {
  if (fd_ < 0) throw GridFileError("cannot open " + path);
}

GridFileHandle::~GridFileHandle() {
  if (fd_ >= 0) ::close(fd_);
}

void GridFileHandle::read(void* out, std::size_t bytes, std::int64_t at) const {
  auto* p = static_cast<char*>(out);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd_, p, bytes, static_cast<off_t>(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw GridFileError("cannot read rows of the grid file " + path_);
    p += n, bytes -= static_cast<std::size_t>(n), at += n;
  }
}

void GridFileHandle::write(const void* in, std::size_t bytes, std::int64_t at, double fileBytes) const {
  const auto* p = static_cast<const char*>(in);
  while (bytes > 0) {
    errno = 0;
    const ssize_t n = ::pwrite(fd_, p, bytes, static_cast<off_t>(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (lacksSpace(path_, errno, fileBytes)) throw DiskFull(path_.substr(path_.find_last_of('/') + 1));
      throw GridFileError("cannot write " + path_);
    }
    p += n, bytes -= static_cast<std::size_t>(n), at += n;
  }
}

GridFileWriter::GridFileWriter(std::string path, const GridGeometry& g)
    : path_(std::move(path)), bytes_(static_cast<double>(g.cellCount()) * 4.0) {
  errno = 0;
  f_ = std::fopen(path_.c_str(), "wb");
  if (!f_) failWrite(path_, errno, bytes_);
}

GridFileWriter::~GridFileWriter() {
  if (f_) std::fclose(f_);
}

void GridFileWriter::append(const float* values, std::size_t n) {
  errno = 0;
  if (std::fwrite(values, sizeof(float), n, f_) != n) failWrite(path_, errno, bytes_);  // little-endian hosts
}

void GridFileWriter::close() {
  errno = 0;
  const int failed = std::fclose(f_);
  f_ = nullptr;
  if (failed != 0) failWrite(path_, errno, bytes_);
}

void GridFileWriter::flush() {
  errno = 0;
  if (std::fflush(f_) != 0) failWrite(path_, errno, bytes_);
}

void GridRowsGate::publish(int rows) {
  {
    std::lock_guard lock(mutex_);
    rows_ = std::max(rows_, rows);
  }
  changed_.notify_all();
}

void GridRowsGate::abort() {
  {
    std::lock_guard lock(mutex_);
    aborted_ = true;
  }
  changed_.notify_all();
}

void GridRowsGate::waitFor(int rows) const {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return aborted_ || rows_ >= rows; });
  if (aborted_) throw GridFileError("the grid file's stream ended early");
}

void readGridRows(const std::string& path, int cols, int row0, int rows, float* out) {
  const GridFileHandle f(path, O_RDONLY);
  f.read(out, static_cast<std::size_t>(rows) * cols * sizeof(float), static_cast<std::int64_t>(row0) * cols * 4);
}

terrain::Traversability traversabilityOfGridFile(const std::string& path, const GridGeometry& g,
                                                 const std::vector<double>& rowCellWidth, int bandRows,
                                                 const std::function<void(const float*, std::size_t)>& eachBand,
                                                 const GridRowsGate* gate, unsigned threads) {
  terrain::Traversability out;
  out.classes = Raster<std::uint8_t>(g, 0);
  bandRows = std::max(1, bandRows);
  const std::size_t bands = static_cast<std::size_t>((g.rows + bandRows - 1) / bandRows);
  // Each band's class counts in its own slot (summed after, in band order): the shares do not
  // depend on the thread count. `eachBand` takes turns in row order (`turn`: the next band's).
  std::vector<std::array<std::int64_t, 4>> counts(bands, std::array<std::int64_t, 4>{});
  std::mutex turnMutex;
  std::condition_variable turnChanged;
  std::size_t turn = 0;
  bool failed = false;  // a band threw: the bands waiting for their turn stop too
  const auto oneBand = [&](std::size_t b) {
    const int r0 = static_cast<int>(b) * bandRows, r1 = std::min(g.rows, r0 + bandRows);
    const int top = std::max(0, r0 - 1), bottom = std::min(g.rows, r1 + 1);  // the halo rows
    terrain::Dem band;
    band.z = Raster<float>(GridGeometry{bottom - top, g.cols, g.cellWidth, g.cellHeight}, 0.0f);
    if (gate) gate->waitFor(bottom);
    readGridRows(path, g.cols, top, bottom - top, band.z.values.data());
    if (eachBand) {
      std::unique_lock lock(turnMutex);
      turnChanged.wait(lock, [&] { return turn == b || failed; });
      if (failed) return;  // another band failed: parallelFor rethrows its error, not a second one
      // The turn passes on even if eachBand throws, so no later band waits for ever.
      struct Pass {
        std::size_t& turn;
        std::condition_variable& changed;
        ~Pass() {
          ++turn;
          changed.notify_all();
        }
      } pass{turn, turnChanged};
      eachBand(&band.z(r0 - top, 0), static_cast<std::size_t>(r1 - r0) * g.cols);
    }
    if (!rowCellWidth.empty()) band.rowCellWidth.assign(rowCellWidth.begin() + top, rowCellWidth.begin() + bottom);
    // A halo row alone (the band's first or last row off the map's edge) would miss its own
    // neighbours, so only the band's own rows are kept.
    const terrain::Traversability t = terrain::traversability(band, {}, false, 1);
    for (int r = r0; r < r1; ++r) {
      const std::uint8_t* from = &t.classes(r - top, 0);
      std::copy(from, from + g.cols, &out.classes(r, 0));
      for (int c = 0; c < g.cols; ++c) ++counts[b][from[c]];
    }
  };
  parallelFor(bands, threads, [&](std::size_t b) {
    try {
      oneBand(b);
    } catch (...) {
      {
        std::lock_guard lock(turnMutex);
        failed = true;
      }
      turnChanged.notify_all();
      throw;
    }
  });
  for (const auto& c : counts)
    for (std::size_t k = 0; k < c.size(); ++k) out.shares.counts[k] += c[k];
  return out;
}

}  // namespace rover::maps
