#include "maps/gdal_env.hpp"

#include <gdal.h>

#include <mutex>

namespace rover::maps {

void ensureGdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);
  });
}

std::string gdalVersion() {
  return std::string("GDAL ") + GDALVersionInfo("RELEASE_NAME");
}

}  // namespace rover::maps
