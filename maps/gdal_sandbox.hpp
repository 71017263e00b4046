#pragma once
// What GDAL may reach while an UploadSandbox is live (gdal_env.hpp), shared by the sandbox
// (gdal_env.cpp: its scope and path rules) and the guards GDAL is fitted with once per process
// (gdal_guards.cpp: wrapped file systems, refused HTTP, gated drivers). Not for other callers.
#include <string>
#include <vector>

#include "maps/gdal_env.hpp"

namespace rover::maps {

struct UploadSandbox::State {
  std::string root;     // canonical (local) or lexically normal (/vsimem/), no trailing '/'
  bool memory = false;  // a /vsimem/ root (the fuzz harness)
  bool allowHdf5 = false;
  std::vector<std::string> refusedFiles, refusedDrivers;
};


namespace sandbox {

// The live sandbox of this thread, if any (UploadSandbox's lifetime).
extern thread_local UploadSandbox::State* tlsSandbox;

// `p` equals `dir` or lies below it (both canonical or lexically normal).
bool underDir(const std::string& p, const std::string& dir);
// Absolute, symlinks and ".." resolved as far as the path exists; "" when it cannot be resolved.
std::string canonicalLocal(const std::string& p);
// The last component of a path.
std::string baseName(const std::string& p);
// Notes a file GDAL was refused, by its base name (once, whatever its case).
void noteRefusedFile(UploadSandbox::State& s, const char* path);

// Fits GDAL with the process-wide guards (once, from ensureGdal): every file system wrapped so a
// live sandbox decides what it reaches (`gdalDataDir`, GDAL's own support files, stays readable),
// network file systems, GDAL's HTTP client and PROJ networking off, and every driver outside
// uploadDrivers() gated.
void installGdalGuards(const std::string& gdalDataDir);

}  // namespace sandbox

}  // namespace rover::maps
