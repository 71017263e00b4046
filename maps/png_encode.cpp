#include "maps/render.hpp"

// encodePng: an Image as PNG bytes through GDAL's PNG driver in memory.
#include <cpl_conv.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <atomic>
#include <stdexcept>
#include <string>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"

namespace rover::maps {

std::vector<std::uint8_t> encodePng(const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != std::size_t(image.width) * image.height * 4)
    throw Error(ErrorCode::InvalidInput, "image",
                "image buffer does not hold width × height RGBA pixels");
  ensureGdal();

  GDALDriverH memDriver = GDALGetDriverByName("MEM");
  GDALDriverH pngDriver = GDALGetDriverByName("PNG");
  if (memDriver == nullptr || pngDriver == nullptr)
    throw std::runtime_error("PNG export: GDAL lacks the MEM or PNG driver");

  const char* memOptions[] = {"INTERLEAVE=PIXEL", nullptr};
  GDALDatasetH src = GDALCreate(memDriver, "", image.width, image.height, 4, GDT_Byte,
                                const_cast<char**>(memOptions));
  if (src == nullptr) throw std::runtime_error(std::string("PNG export: ") + CPLGetLastErrorMsg());
  // GF_Write only reads the buffer.
  auto* data = const_cast<std::uint8_t*>(image.rgba.data());
  if (GDALDatasetRasterIO(src, GF_Write, 0, 0, image.width, image.height, data, image.width,
                          image.height, GDT_Byte, 4, nullptr, 4, 4 * image.width, 1) != CE_None) {
    GDALClose(src);
    throw std::runtime_error(std::string("PNG export: ") + CPLGetLastErrorMsg());
  }
  const GDALColorInterp interp[4] = {GCI_RedBand, GCI_GreenBand, GCI_BlueBand, GCI_AlphaBand};
  for (int b = 0; b < 4; ++b) GDALSetRasterColorInterpretation(GDALGetRasterBand(src, b + 1), interp[b]);

  static std::atomic<unsigned long long> counter{0};
  const std::string path = "/vsimem/rover_render_" + std::to_string(counter.fetch_add(1)) + ".png";
  // ZLEVEL=1: measured on a full 4096² hillshaded elevation map, level 1 encodes in ~0.8 s
  // against ~2.7 s for zlib's default 6, for a file ~1.5× larger (8.0 vs 5.4 MB); renderings are
  // made on request, so encoding time matters more than bytes.
  const char* pngOptions[] = {"ZLEVEL=1", nullptr};
  GDALDatasetH dst = GDALCreateCopy(pngDriver, path.c_str(), src, FALSE,
                                    const_cast<char**>(pngOptions), nullptr, nullptr);
  GDALClose(src);
  if (dst == nullptr) {
    VSIUnlink(path.c_str());
    throw std::runtime_error(std::string("PNG export: ") + CPLGetLastErrorMsg());
  }
  GDALClose(dst);

  std::vector<std::uint8_t> bytes = takeMemFile(path);
  VSIUnlink((path + ".aux.xml").c_str());  // in case PAM wrote one
  if (bytes.empty()) throw std::runtime_error("PNG export: the PNG driver wrote nothing");
  return bytes;
}

}  // namespace rover::maps
