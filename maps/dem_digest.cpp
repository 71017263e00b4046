#include "maps/dem_digest.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

namespace rover::maps {

namespace {

static_assert(std::endian::native == std::endian::little, "the digest is defined little-endian");

struct Digest {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx{EVP_MD_CTX_new(), &EVP_MD_CTX_free};
  Digest() {
    if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1)
      throw std::runtime_error("SHA-256 is not available");
  }
  void add(const void* p, std::size_t n) { EVP_DigestUpdate(ctx.get(), p, n); }
  template <class T>
  void value(T v) { add(&v, sizeof v); }
  std::string hex() {
    unsigned char out[EVP_MAX_MD_SIZE];
    unsigned int n = 0;
    EVP_DigestFinal_ex(ctx.get(), out, &n);
    static const char* digits = "0123456789abcdef";
    std::string s;
    for (unsigned i = 0; i < n; ++i) {
      s.push_back(digits[out[i] >> 4]);
      s.push_back(digits[out[i] & 15]);
    }
    return s;
  }
};

}  // namespace

struct DemDigest::State {
  Digest sha;
  std::vector<float> block;
};

DemDigest::DemDigest(const GridGeometry& g, const std::vector<double>& rowCellWidth) : state_(std::make_unique<State>()) {
  Digest& d = state_->sha;
  static const char tag[] = "roverplan-dem-v1";
  d.add(tag, sizeof tag - 1);
  d.value<std::int64_t>(g.rows);
  d.value<std::int64_t>(g.cols);
  d.value<double>(g.cellWidth);
  d.value<double>(g.cellHeight);
  d.value<std::int64_t>(static_cast<std::int64_t>(rowCellWidth.size()));
  if (!rowCellWidth.empty()) d.add(rowCellWidth.data(), rowCellWidth.size() * sizeof(double));
}

DemDigest::~DemDigest() = default;

void DemDigest::add(const float* z, std::size_t n) {
  // In blocks, so NaNs (any payload) are written as one value without copying the whole grid.
  const float canonicalNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<float>& block = state_->block;
  for (std::size_t i = 0; i < n; i += 1 << 16) {
    const std::size_t m = std::min<std::size_t>(1 << 16, n - i);
    block.assign(z + i, z + i + m);
    for (float& v : block)
      if (std::isnan(v)) v = canonicalNaN;
    state_->sha.add(block.data(), m * sizeof(float));
  }
}

std::string DemDigest::hex() { return state_->sha.hex(); }

std::string demSha256(const terrain::Dem& dem) {
  DemDigest d(dem.geometry(), dem.rowCellWidth);
  d.add(dem.z.values.data(), static_cast<std::size_t>(dem.z.values.size()));  // row-major, row 0 at the top
  return d.hex();
}

}  // namespace rover::maps
