#pragma once
// The one way a DEM reader refuses a file: rover::Error (InvalidInput) naming the field, with a
// message "FILE: reason" where FILE is the name the user gave (an upload's own name, never a
// server path).
#include <string>

#include "core/common/error.hpp"

namespace rover::maps {

[[noreturn]] inline void failFile(const std::string& shownPath, const std::string& reason,
                                  const std::string& field = "file") {
  throw Error(ErrorCode::InvalidInput, field, shownPath + ": " + reason);
}

// Whether a failed raster write into `path`'s folder was the disk's fault: errno `err` (ENOSPC,
// EDQUOT, EFBIG), GDAL's last message, or less free space there than `bytes` plus 64 KiB (libtiff
// often names only the symptom). dem_io.cpp.
bool lacksSpace(const std::string& path, int err, double bytes);

// A number as the warper and messages take it: 17 significant digits, no trailing zeros.
std::string exactNumber(double v);

}  // namespace rover::maps
