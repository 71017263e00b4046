// libFuzzer harness: DEM ingest from bytes (issue 14). The input becomes one or two files in a
// /vsimem/ folder of this run, opened through the same restricted open as an upload
// (maps::UploadSandbox + maps::loadDem with `upload` set: driver allow-list, file-list check) and
// read into the project's raster as an import reads it, under a small cell budget.
//
// Input layout: byte 0 picks the main file's extension (the driver GDAL tries first depends on it);
// the rest is its content. When the content holds the separator "\n--8<--\n", what follows becomes
// a second file named as that format's companion (.hdr for .img/.bil, .img for a .lbl or PDS4 .xml
// label, FILE.aux.xml otherwise).
#include <cpl_string.h>
#include <cpl_vsi.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"

namespace {

const char* const kExtensions[] = {".tif", ".img", ".lbl", ".asc", ".xyz", ".cub", ".grd", ".nc",
                                   ".png", ".xml", ".hgt", ".dem", ".dt0", ".bil", ".zip"};

std::string companion(const std::string& ext, const std::string& main) {
  if (ext == ".img" || ext == ".bil") return "dem.hdr";
  if (ext == ".lbl" || ext == ".xml") return "dem.img";
  return main + ".aux.xml";
}

void writeMem(const std::string& path, const std::string& bytes) {
  VSILFILE* f = VSIFOpenL(path.c_str(), "wb");
  if (!f) return;
  VSIFWriteL(bytes.data(), 1, bytes.size(), f);
  VSIFCloseL(f);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  rover::maps::ensureGdal();
  static const std::string runRoot = "/vsimem/fuzz-dem-" + std::to_string(::getpid());
  static unsigned long counter = 0;
  const std::string root = runRoot + "/" + std::to_string(counter++);
  VSIMkdirRecursive(root.c_str(), 0755);

  const std::string ext = kExtensions[data[0] % (sizeof(kExtensions) / sizeof(kExtensions[0]))];
  std::string content(reinterpret_cast<const char*>(data) + 1, size - 1), second;
  const std::string separator = "\n--8<--\n";
  if (auto at = content.find(separator); at != std::string::npos) {
    second = content.substr(at + separator.size());
    content.resize(at);
  }
  const std::string main = "dem" + ext;
  writeMem(root + "/" + main, content);
  if (!second.empty()) writeMem(root + "/" + companion(ext, main), second);

  std::string path = root + "/" + main;
  if (ext == ".zip") {  // an import opens the first member of an archive as /vsizip/ARCHIVE/member
    char** members = VSIReadDirRecursive(("/vsizip/" + path).c_str());
    if (members && members[0]) path = "/vsizip/" + path + "/" + members[0];
    CSLDestroy(members);
  }
  {
    rover::maps::UploadSandbox sandbox(root);
    rover::maps::LoadOptions o;
    o.upload = &sandbox;
    o.maxCells = 1 << 20;  // the pixel budget, checked before anything is read
    // ROVER_FUZZ_VERBOSE=1 prints each outcome (to check that the seeds load).
    static const bool verbose = std::getenv("ROVER_FUZZ_VERBOSE") != nullptr;
    try {
      rover::maps::LoadedDem d = rover::maps::loadDem(path, o);
      if (verbose)
        std::fprintf(stderr, "loaded %s: %s %d x %d\n", main.c_str(), d.info.driver.c_str(),
                     d.dem.geometry().rows, d.dem.geometry().cols);
    } catch (const rover::Error& e) {
      // a refused or unreadable input: the expected outcome for most bytes
      if (verbose) std::fprintf(stderr, "refused %s: %s\n", main.c_str(), e.what());
    }
  }
  VSIRmdirRecursive(root.c_str());
  return 0;
}
