#include "maps/block_cache.hpp"

#include <cpl_error.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace rover::maps {

namespace {

// A block of one level of one file, the file known by its path and stat identity.
struct BlockKey {
  std::string path;
  dev_t dev;
  ino_t ino;
  off_t size;
  long long mtimeSec, mtimeNsec;
  int levelCols, levelRows;  // the band's size: a file's levels all differ in size
  int bx, by;
  bool operator==(const BlockKey&) const = default;
};

struct BlockKeyHash {
  std::size_t operator()(const BlockKey& k) const {
    std::size_t h = std::hash<std::string>()(k.path);
    for (long long v : {static_cast<long long>(k.ino), static_cast<long long>(k.size), k.mtimeNsec,
                        static_cast<long long>(k.levelCols), static_cast<long long>(k.bx),
                        static_cast<long long>(k.by)})
      h = h * 1099511628211ull ^ std::hash<long long>()(v);
    return h;
  }
};

// A decoded block's bytes, left uninitialised until the decoder writes them (a zero fill first
// was a pass over fresh pages for nothing).
struct Bytes {
  explicit Bytes(std::size_t n) : bytes(new unsigned char[n]), n(n) {}
  unsigned char* data() { return bytes.get(); }
  const unsigned char* data() const { return bytes.get(); }
  std::size_t size() const { return n; }
  std::unique_ptr<unsigned char[]> bytes;
  std::size_t n;
};

class DecodedBlocks {
 public:
  static DecodedBlocks& instance() {
    static DecodedBlocks d;
    return d;
  }

  std::shared_ptr<const Bytes> find(const BlockKey& k) {
    std::lock_guard lock(mutex_);
    auto it = index_.find(k);
    if (it == index_.end()) return nullptr;
    lru_.splice(lru_.begin(), lru_, it->second);
    return it->second->bytes;
  }

  // A buffer of `n` bytes to decode into: an evicted block's when one of that size is free (no
  // fresh pages to fault in a block), else a new one.
  std::shared_ptr<Bytes> buffer(std::size_t n) {
    {
      std::lock_guard lock(mutex_);
      for (auto it = spare_.begin(); it != spare_.end(); ++it)
        if ((*it)->size() == n) {
          std::shared_ptr<Bytes> b = std::move(*it);
          spare_.erase(it);
          return b;
        }
    }
    return std::make_shared<Bytes>(n);
  }

  // `bytes` as the block `k` (another thread may have put it there meanwhile: that one is kept).
  std::shared_ptr<const Bytes> put(const BlockKey& k, std::shared_ptr<Bytes> bytes) {
    std::lock_guard lock(mutex_);
    if (auto it = index_.find(k); it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      return it->second->bytes;
    }
    total_ += bytes->size();
    lru_.push_front(Entry{k, bytes});
    index_.emplace(k, lru_.begin());
    while (total_ > kDecodedBlockBytes && lru_.size() > 1) dropLocked(std::prev(lru_.end()));
    return bytes;
  }

  void forget(const std::string& prefix) {
    std::lock_guard lock(mutex_);
    for (auto it = lru_.begin(); it != lru_.end();) {
      auto next = std::next(it);
      if (it->key.path.rfind(prefix, 0) == 0) dropLocked(it);
      it = next;
    }
    spare_.clear();
  }

 private:
  struct Entry {
    BlockKey key;
    std::shared_ptr<Bytes> bytes;
  };
  static constexpr std::size_t kSpare = 8;

  void dropLocked(std::list<Entry>::iterator it) {
    total_ -= it->bytes->size();
    index_.erase(it->key);
    // Reused by the next decode unless a reader still holds it (then freed by its last reader).
    if (it->bytes.use_count() == 1 && spare_.size() < kSpare) spare_.push_back(std::move(it->bytes));
    lru_.erase(it);
  }

  std::mutex mutex_;
  std::list<Entry> lru_;  // most recently used first
  std::unordered_map<BlockKey, std::list<Entry>::iterator, BlockKeyHash> index_;
  std::vector<std::shared_ptr<Bytes>> spare_;
  std::size_t total_ = 0;
};

}  // namespace

bool readThroughBlocks(GDALDatasetH ds, GDALRasterBandH band, const std::string& path, const struct stat& id, int c0,
                       int r0, int cols, int rows, void* out, GDALDataType type) {
  GDALDriverH driver = GDALGetDatasetDriver(ds);
  if (!driver || std::strcmp(GDALGetDriverShortName(driver), "GTiff") != 0) return false;
  if (GDALGetRasterDataType(band) != type) return false;
  int bw = 0, bh = 0;
  GDALGetBlockSize(band, &bw, &bh);
  const std::size_t cell = static_cast<std::size_t>(GDALGetDataTypeSizeBytes(type));
  if (bw <= 0 || bh <= 0 || cell == 0 || std::size_t(bw) * bh * cell > (std::size_t(4) << 20)) return false;
  const int levelCols = GDALGetRasterBandXSize(band), levelRows = GDALGetRasterBandYSize(band);
  if (c0 < 0 || r0 < 0 || cols <= 0 || rows <= 0 || c0 + cols > levelCols || r0 + rows > levelRows) return false;

  DecodedBlocks& cache = DecodedBlocks::instance();
  BlockKey key{path, id.st_dev, id.st_ino, id.st_size, id.st_mtim.tv_sec, id.st_mtim.tv_nsec, levelCols, levelRows, 0, 0};
  auto* dst = static_cast<unsigned char*>(out);
  for (int by = r0 / bh; by <= (r0 + rows - 1) / bh; ++by)
    for (int bx = c0 / bw; bx <= (c0 + cols - 1) / bw; ++bx) {
      key.bx = bx;
      key.by = by;
      std::shared_ptr<const Bytes> block = cache.find(key);
      if (!block) {
        std::shared_ptr<Bytes> fresh = cache.buffer(std::size_t(bw) * bh * cell);
        CPLErrorReset();
        if (GDALReadBlock(band, bx, by, fresh->data()) != CE_None)
          throw std::runtime_error("cannot read a block of the stored raster " + path + " (" + CPLGetLastErrorMsg() + ")");
        block = cache.put(key, std::move(fresh));
      }
      // The part of the window in this block, row by row.
      const int bc0 = std::max(c0, bx * bw), bc1 = std::min(c0 + cols, (bx + 1) * bw);
      const int br0 = std::max(r0, by * bh), br1 = std::min(r0 + rows, (by + 1) * bh);
      const std::size_t run = std::size_t(bc1 - bc0) * cell;
      for (int r = br0; r < br1; ++r)
        std::memcpy(dst + (std::size_t(r - r0) * cols + (bc0 - c0)) * cell,
                    block->data() + (std::size_t(r - by * bh) * bw + (bc0 - bx * bw)) * cell, run);
    }
  return true;
}

void forgetDecodedBlocks(const std::string& dir) {
  std::string prefix = dir;
  if (!prefix.empty() && prefix.back() != '/') prefix += '/';
  DecodedBlocks::instance().forget(prefix);
}

}  // namespace rover::maps
