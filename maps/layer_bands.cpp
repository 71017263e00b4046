#include "maps/layer_bands.hpp"

#include <cpl_error.h>
#include <gdal.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"

namespace rover::maps {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace

LayerBands::LayerBands(const std::string& demPath, const DemHeader& header, RenderLayer layer)
    : path_(demPath), header_(header), layer_(layer) {
  if (layer != RenderLayer::Elevation && layer != RenderLayer::Slope && layer != RenderLayer::Hillshade)
    throw Error(ErrorCode::InvalidInput, "layer", "layers computed in bands are elevation, slope and hillshade");
  ensureGdal();
  GdalErrorLog errors;
  ds_.reset(GDALOpenEx(path_.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  const GridGeometry& g = header_.geometry;
  if (!ds_ || GDALGetRasterCount(ds_.get()) < 1 || GDALGetRasterXSize(ds_.get()) != g.cols ||
      GDALGetRasterYSize(ds_.get()) != g.rows)
    throw std::runtime_error("cannot read the stored raster " + path_ + " as its header says");
  GDALRasterBandH band = GDALGetRasterBand(ds_.get(), 1);
  // A stored map's heights are the import's (its scale and offset applied): only nodata is read
  // as loadDem reads it.
  int has = 0;
  if (GDALGetRasterScale(band, &has) != 1.0 || GDALGetRasterOffset(band, &has) != 0.0)
    throw std::runtime_error("the stored raster " + path_ + " has a scale or an offset");
  const double nodata = GDALGetRasterNoDataValue(band, &has);
  hasNodata_ = has != 0 && !std::isnan(nodata);  // NaN cells are NaN already
  nodata_ = static_cast<float>(nodata);
  // Whole rows of blocks at a time (the COG's 128, an older map's 256), so no block is decoded
  // twice; a file of one-row blocks (a raw grid) is read 128 rows at a time.
  int blockCols = 0, blockRows = 0;
  GDALGetBlockSize(band, &blockCols, &blockRows);
  chunk_ = blockRows >= 16 && blockRows <= 256 ? blockRows : 128;
}

void LayerBands::readTo(int row) {
  const GridGeometry& g = header_.geometry;
  GDALRasterBandH band = GDALGetRasterBand(ds_.get(), 1);
  while (hi_ < row) {
    const int end = std::min(g.rows, (hi_ / chunk_ + 1) * chunk_);
    heights_.resize(static_cast<std::size_t>(end - lo_) * g.cols);
    float* into = heights_.data() + static_cast<std::size_t>(hi_ - lo_) * g.cols;
    GdalErrorLog errors;
    // A raw map's VRT reads its grid file's rows straight into `into` (a raw band otherwise keeps
    // every row it reads in GDAL's block cache: 256 MiB, the cache's cap, for a 7000² map).
    const ThreadConfig direct("GDAL_ONE_BIG_READ", "YES");
    if (GDALRasterIO(band, GF_Read, 0, hi_, g.cols, end - hi_, into, g.cols, end - hi_, GDT_Float32, 0, 0) != CE_None)
      throw std::runtime_error("cannot read rows of the stored raster " + path_ + " (" + CPLGetLastErrorMsg() + ")");
    // Its blocks are read once: dropped now rather than kept in GDAL's block cache, which a sweep
    // of the whole map would fill.
    GDALFlushCache(ds_.get());
    if (hasNodata_)
      for (float* v = into, *e = heights_.data() + heights_.size(); v != e; ++v)
        if (*v == nodata_) *v = kNaN;
    hi_ = end;
  }
}

void LayerBands::dropAbove(int row) {
  const int cols = header_.geometry.cols;
  if (row <= lo_) return;
  const auto from = heights_.begin() + static_cast<std::ptrdiff_t>(row - lo_) * cols;
  std::copy(from, heights_.end(), heights_.begin());
  heights_.resize(static_cast<std::size_t>(hi_ - row) * cols);
  lo_ = row;
}

int LayerBands::next(float* out) {
  const GridGeometry& g = header_.geometry;
  if (done_ >= g.rows) return 0;
  const int r0 = done_, r1 = std::min(g.rows, r0 + kBandRows);
  const std::size_t cols = static_cast<std::size_t>(g.cols);
  if (layer_ == RenderLayer::Elevation) {
    readTo(r1);
    std::copy_n(heights_.data() + (r0 - lo_) * cols, (r1 - r0) * cols, out);
    dropAbove(r1);
  } else {
    // The band with its halo: rows [top, bottom) of the map. Its first and last rows are NaN in
    // the layer (Horn's border), which the map's are too; the band's own rows in between are
    // interior rows of the band wherever they are interior rows of the map.
    const int top = std::max(0, r0 - 1), bottom = std::min(g.rows, r1 + 1);
    readTo(bottom);
    terrain::Dem band;
    band.z = Raster<float>(GridGeometry{bottom - top, g.cols, g.cellWidth, g.cellHeight}, 0.0f);
    std::copy_n(heights_.data() + (top - lo_) * cols, (bottom - top) * cols, band.z.values.data());
    if (!header_.rowCellWidth.empty())
      band.rowCellWidth.assign(header_.rowCellWidth.begin() + top, header_.rowCellWidth.begin() + bottom);
    const Raster<float> values = layer_ == RenderLayer::Slope ? terrain::slopeHorn(band) : terrain::hillshade(band);
    std::copy_n(&values(r0 - top, 0), (r1 - r0) * cols, out);
    dropAbove(r1 - 1);  // the next band's halo row above
  }
  done_ = r1;
  return r1 - r0;
}

}  // namespace rover::maps
