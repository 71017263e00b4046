#pragma once
// GDAL process setup for the map data layer: drivers registered once, errors kept off stderr so
// they reach users as our own messages, network access off — and the one door every user-supplied
// raster comes in by (issue 14): an allow-list of raster drivers, reads confined to the upload's
// own folder, and a check of every file the opened dataset uses.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace rover::maps {

// Registers all GDAL drivers and sets the process up (thread-safe, idempotent): errors quiet,
// every network file system (/vsicurl/, /vsis3/, …) and GDAL's HTTP client refused for good, PROJ
// networking off, and the upload guards (UploadSandbox) installed.
void ensureGdal();
// "GDAL 3.6.2" — the runtime library's own release name.
std::string gdalVersion();

// The raster drivers an upload may be read with: GTiff (also COG), PDS (PDS3), PDS4, ISIS3, ISIS2,
// VICAR, netCDF (classic; netCDF-4/HDF5 only under an UploadSandbox that allows it), ENVI, EHdr, AAIGrid,
// XYZ, USGSDEM, SRTMHGT, DTED, HFA, GS7BG, GSBG, GSAG, PNG. No VRT (sources are any path), no
// MEM, no network drivers (WMS, WCS, WMTS, HTTP, DAAS, …), nothing that is not a raster.
const std::vector<std::string>& uploadDrivers();
// The formats in words for messages ("GeoTIFF, PDS3, …").
std::string uploadFormatsInWords();
// A driver's short name in words: GTiff -> "GeoTIFF", PDS -> "PDS3 image", …
std::string formatInWords(const std::string& driver);

// While alive, GDAL on this thread opens and lists local files only inside `root` (compared as
// canonical paths, so symlinks and ".." cannot leave it), no virtual file system but /vsizip/ and
// /vsitar/ (whose archive must itself lie inside) and, for a /vsimem/ root, that folder; and no
// driver outside uploadDrivers() opens anything, also a dataset nested in an allowed one (an
// ISIS3 cube whose core is a VRT). Scopes do not nest. ROVER_SANDBOX_DEBUG=1 in the environment
// prints each refused path to stderr (to see what a format probes).
class UploadSandbox {
 public:
  // `allowHdf5`: netCDF-4 (HDF5) files may be opened. libhdf5 opens the files a dataset links to
  // itself, past GDAL's file guards, so only a process that sees nothing but the upload (the
  // bubblewrap import jail, server/jail/) may allow it.
  explicit UploadSandbox(const std::string& root, bool allowHdf5 = false);
  bool allowsHdf5() const;
  ~UploadSandbox();
  UploadSandbox(const UploadSandbox&) = delete;
  UploadSandbox& operator=(const UploadSandbox&) = delete;

  const std::string& root() const;
  // True while this is the live scope of the calling thread.
  bool live() const;
  // True when `path` (a plain path, or /vsizip/ARCHIVE/member, /vsitar/…) lies inside the root.
  bool contains(const std::string& path) const;
  // `path` as the client named it: relative to the root ("dem.zip/dem.tif"), or only the file
  // name for a path outside (never a server folder).
  std::string uploadName(const std::string& path) const;
  // What GDAL was refused so far: files outside the root (their upload names) and drivers.
  const std::vector<std::string>& refusedFiles() const;
  const std::vector<std::string>& refusedDrivers() const;

  struct State;

 private:
  std::unique_ptr<State> state_;
};

// GDAL dataset handle that closes itself.
struct DatasetCloser {
  void operator()(void* ds) const;
};
using Dataset = std::unique_ptr<void, DatasetCloser>;

// Opens a user-supplied raster read-only under `sandbox` (which must be the live scope of this
// thread) through the allow-list, then checks that every file of the dataset (GetFileList; for an
// archive member, the archive) lies inside the root. `refusal` is set, in words with upload names
// only, when the file is refused for what it is or where it reads (a VRT, a label pointing outside,
// a network path); a null result with an empty refusal means "not a raster we can read".
Dataset openUpload(const std::string& path, const UploadSandbox& sandbox, std::string& refusal);

// GDAL's error messages on this thread while alive (CPLError goes nowhere else meanwhile).
class GdalErrorLog {
 public:
  GdalErrorLog();
  ~GdalErrorLog();
  GdalErrorLog(const GdalErrorLog&) = delete;
  GdalErrorLog& operator=(const GdalErrorLog&) = delete;
  const std::vector<std::string>& messages() const { return messages_; }
  // True when any message contains `text` (case-sensitive).
  bool mentions(const std::string& text) const;
  void add(std::string message) { messages_.push_back(std::move(message)); }

 private:
  std::vector<std::string> messages_;
};

// A GDAL configuration option set on this thread while alive (CPLSetThreadLocalConfigOption),
// its previous thread-local value back afterwards: for an option a driver reads when it opens or
// creates a dataset.
class ThreadConfig {
 public:
  ThreadConfig(const char* key, const char* value);
  ~ThreadConfig();
  ThreadConfig(const ThreadConfig&) = delete;
  ThreadConfig& operator=(const ThreadConfig&) = delete;

 private:
  std::string key_, was_;
  bool had_ = false;
};

// Whether GDAL reported running out of memory (CPLE_OutOfMemory) under any GdalErrorLog of this
// process so far: the import worker, under RLIMIT_AS, answers such a failure 413, not "corrupt".
bool gdalRanOutOfMemory();

// `text` with every absolute path replaced by its last component.
std::string withoutPaths(const std::string& text);

// The first n bytes of a file, read through GDAL (so inside an active UploadSandbox); "" when
// it cannot be read.
std::string firstBytes(const std::string& path, std::size_t n);

// The bytes of the in-memory file `path` (/vsimem/…), which is then removed; empty when there is
// none (the exports' way out of GDAL without touching the disk).
std::vector<std::uint8_t> takeMemFile(const std::string& path);

}  // namespace rover::maps
