#include "maps/render.hpp"

// encodePng: an Image as PNG bytes, written directly (issue 24: cold tile latency). Why this shape
// (figures in .decisions/0004-map-storage-codecs.md):
// - every row takes the "Up" filter (one subtraction a byte): libpng's per-row choice of the best
//   of five filters cost as much as the compression, for files within a few percent;
// - deflate is libdeflate's at level 1 (what GDAL's CPLZLibDeflate calls on Debian), one
//   compressor kept per thread: 2.1-2.3× faster than zlib's and 6-12 % smaller;
// - PngColours::Smallest (tiles) writes the fewest bytes a pixel that still decode to exactly the
//   image's RGBA: grey when every pixel is opaque grey, a palette (PLTE, tRNS; 8 bits a pixel, or
//   1/2/4 for up to 2/4/16 colours) for at most 256 colours, RGB when opaque, else RGBA. The
//   palette is sorted by colour, so neighbouring pixels of a grey keep neighbouring indices;
// - many-colour tiles (elevation, slope: noise-like residuals) take Paeth rows in literal-only
//   deflate blocks (maps/literal_deflate.hpp) instead of libdeflate's match search, unless one
//   byte value is over 3/4 of the rows (runs, transparent areas), where matches pay.
#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include "core/common/error.hpp"
#include "maps/literal_deflate.hpp"

namespace rover::maps {

namespace {

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  const std::uint8_t b[4] = {std::uint8_t(v >> 24), std::uint8_t(v >> 16), std::uint8_t(v >> 8), std::uint8_t(v)};
  out.insert(out.end(), b, b + 4);
}

// A chunk: length, type, data, CRC-32 of type and data.
void chunk(std::vector<std::uint8_t>& out, const char* type, const std::uint8_t* data, std::size_t n) {
  put32(out, static_cast<std::uint32_t>(n));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (n) out.insert(out.end(), data, data + n);
  put32(out, libdeflate_crc32(0, out.data() + start, 4 + n));
}

// This thread's level-1 compressor (its tables are allocated once, not per picture).
libdeflate_compressor* compressor() {
  struct Owned {
    libdeflate_compressor* c = libdeflate_alloc_compressor(1);
    ~Owned() { libdeflate_free_compressor(c); }
  };
  thread_local Owned owned;
  if (owned.c == nullptr) throw std::bad_alloc();
  return owned.c;
}

// A buffer without the zero-fill a std::vector would write first (every byte is written).
using Bytes = std::unique_ptr<std::uint8_t[]>;
Bytes bytes(std::size_t n) { return Bytes(new std::uint8_t[n]); }

// A pixel as one number: red in the low byte, alpha in the high one.
std::uint32_t pixelAt(const std::uint8_t* rgba, std::size_t i) {
  const std::uint8_t* p = rgba + i * 4;
  return p[0] | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}

// The pixels as a palette: up to 256 colours (packed as pixelAt reads them) and each pixel's
// index; false when there are more. With `stride` > 1 only every stride-th pixel is looked at and
// no index is written: more than 256 colours there means more than 256 in all, found for a
// fraction of the work (an elevation or slope tile has its 257th colour late, if it is smooth).
bool toPalette(const Image& image, std::vector<std::uint32_t>& colours, std::uint8_t* index, std::size_t stride = 1) {
  constexpr std::uint32_t kSlots = 1024;  // open addressing, at most a quarter full
  std::array<std::uint32_t, kSlots> keys;
  std::array<std::int16_t, kSlots> slot;
  slot.fill(-1);
  colours.clear();
  const std::size_t n = std::size_t(image.width) * image.height;
  const std::uint8_t* px = image.rgba.data();
  std::uint32_t last = ~pixelAt(px, 0);  // not the first pixel: it is looked up
  std::uint8_t lastIndex = 0;
  for (std::size_t i = 0; i < n; i += stride) {
    const std::uint32_t k = pixelAt(px, i);
    if (k != last) {  // runs of one colour (flat ground, beyond the map) skip the lookup
      std::uint32_t h = (k * 2654435761u) >> 22;
      while (slot[h] >= 0 && keys[h] != k) h = (h + 1) & (kSlots - 1);
      if (slot[h] < 0) {
        if (colours.size() == 256) return false;
        keys[h] = k;
        slot[h] = static_cast<std::int16_t>(colours.size());
        colours.push_back(k);
      }
      last = k;
      lastIndex = static_cast<std::uint8_t>(slot[h]);
    }
    if (stride == 1) index[i] = lastIndex;
  }
  return true;
}

constexpr std::uint8_t kUp = 2, kPaeth = 4;

// `h` rows of `rowBytes` from `raw` filtered into `out` (a filter byte, then the row), the row
// above the first one being zeros: Up, each byte minus the one above; Paeth, minus whichever of
// left (a), above (b) and above-left (c) is nearest a + b − c, ties in that order.
void filterRows(const std::uint8_t* raw, std::size_t h, std::size_t rowBytes, std::size_t bpp, std::uint8_t filter,
                std::uint8_t* out) {
  std::vector<std::uint8_t> zeros(rowBytes, 0);
  for (std::size_t y = 0; y < h; ++y) {
    std::uint8_t* o = out + y * (rowBytes + 1);
    const std::uint8_t* row = raw + y * rowBytes;
    const std::uint8_t* up = y ? row - rowBytes : zeros.data();
    o[0] = filter;
    ++o;
    if (filter == kUp) {
      for (std::size_t i = 0; i < rowBytes; ++i) o[i] = static_cast<std::uint8_t>(row[i] - up[i]);
      continue;
    }
    for (std::size_t i = 0; i < bpp && i < rowBytes; ++i) o[i] = static_cast<std::uint8_t>(row[i] - up[i]);
    // In 16-bit lanes (|a + b − 2c| ≤ 510 fits): twice the bytes a vector of 32-bit ones.
    for (std::size_t i = bpp; i < rowBytes; ++i) {
      const std::int16_t a = row[i - bpp], b = up[i], c = up[i - bpp];
      const std::int16_t db = static_cast<std::int16_t>(b - c), da = static_cast<std::int16_t>(a - c);
      const std::int16_t pa = static_cast<std::int16_t>(db < 0 ? -db : db);
      const std::int16_t pb = static_cast<std::int16_t>(da < 0 ? -da : da);
      const std::int16_t sum = static_cast<std::int16_t>(da + db);
      const std::int16_t pc = static_cast<std::int16_t>(sum < 0 ? -sum : sum);
      const std::int16_t pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      o[i] = static_cast<std::uint8_t>(row[i] - pred);
    }
  }
}

}  // namespace

std::vector<std::uint8_t> encodePng(const Image& image, PngColours colours) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != std::size_t(image.width) * image.height * 4)
    throw Error(ErrorCode::InvalidInput, "image",
                "image buffer does not hold width × height RGBA pixels");
  const std::size_t w = image.width, h = image.height, n = w * h;
  const std::uint8_t* px = image.rgba.data();

  // 1. The layout: colour type, bits a pixel, and the unfiltered rows (`raw`, rowBytes each).
  int colourType = 6, bitDepth = 8;
  std::vector<std::uint32_t> palette;
  Bytes packed;
  const std::uint8_t* raw = px;  // RGBA: the image's own rows
  if (colours == PngColours::Smallest) {
    // Branch-free over whole pixels (the compiler vectorises it): every alpha 255, every
    // red = green = blue.
    std::uint32_t alphas = 0xff000000u, spread = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t v = pixelAt(px, i);
      alphas &= v;
      spread |= (v ^ (v >> 8)) & 0xffffu;
    }
    const bool opaque = alphas == 0xff000000u, grey = spread == 0;
    Bytes index;
    if (grey && opaque) {
      colourType = 0;
    } else if (index = bytes(n); toPalette(image, palette, nullptr, 7) && toPalette(image, palette, index.get())) {
      colourType = 3;
      bitDepth = palette.size() <= 2 ? 1 : palette.size() <= 4 ? 2 : palette.size() <= 16 ? 4 : 8;
    } else if (opaque) {
      colourType = 2;
    }
    if (colourType == 3) {
      // Translucent entries first (tRNS lists only those), then by red, green, blue.
      auto key = [](std::uint32_t c) {
        const std::uint64_t a = c >> 24, r = c & 0xff, g = (c >> 8) & 0xff, b = (c >> 16) & 0xff;
        return (std::uint64_t(a == 255) << 32) | (r << 24) | (g << 16) | (b << 8) | a;
      };
      std::vector<std::uint8_t> order(palette.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint8_t>(i);
      std::sort(order.begin(), order.end(), [&](std::uint8_t a, std::uint8_t b) { return key(palette[a]) < key(palette[b]); });
      std::array<std::uint8_t, 256> rank{};
      std::vector<std::uint32_t> sorted(palette.size());
      for (std::size_t i = 0; i < order.size(); ++i) {
        rank[order[i]] = static_cast<std::uint8_t>(i);
        sorted[i] = palette[order[i]];
      }
      palette = std::move(sorted);
      const std::size_t rowBytes = (w * bitDepth + 7) / 8;
      packed = bytes(h * rowBytes);
      const int perByte = 8 / bitDepth;
      for (std::size_t y = 0; y < h; ++y) {
        const std::uint8_t* in = index.get() + y * w;
        std::uint8_t* out = packed.get() + y * rowBytes;
        if (bitDepth == 8) {
          for (std::size_t x = 0; x < w; ++x) out[x] = rank[in[x]];
          continue;
        }
        // Leftmost pixel in the high bits; a byte at a time, in a register (a division and a
        // read-modify-write of memory a pixel were a fifth of a traversability tile's encoding).
        for (std::size_t at = 0, x = 0; at < rowBytes; ++at) {
          unsigned v = 0;
          for (int k = 0; k < perByte; ++k, ++x)  // past the row's end: zero bits
            v = v << bitDepth | (x < w ? rank[in[x]] : 0u);
          out[at] = static_cast<std::uint8_t>(v);
        }
      }
      raw = packed.get();
    } else if (colourType == 0 || colourType == 2) {
      const std::size_t channels = colourType == 0 ? 1 : 3;
      packed = bytes(n * channels + 1);  // + 1: RGB rows are copied 4 bytes a pixel (below)
      std::uint8_t* out = packed.get();
      if (channels == 1)
        for (std::size_t i = 0; i < n; ++i) out[i] = px[i * 4];
      else  // each pixel's 4 bytes, the next one's red overwriting its alpha: one store a pixel
        for (std::size_t i = 0; i < n; ++i) std::memcpy(out + i * 3, px + i * 4, 4);
      raw = packed.get();
    }
  }
  const int channels = colourType == 6 ? 4 : colourType == 2 ? 3 : 1;
  const std::size_t rowBytes = (w * channels * bitDepth + 7) / 8;

  // 2. The filtered rows, then deflate. Many colours (RGB, RGBA) in Smallest: Paeth rows in
  // literal-only blocks (maps/literal_deflate.hpp), unless one byte value is over 3/4 of them (runs).
  // Otherwise, and when that gives up: "Up" rows and libdeflate.
  const std::size_t filteredSize = h * (rowBytes + 1);
  Bytes rows = bytes(filteredSize);
  std::vector<std::uint8_t> idat;
  if (colours == PngColours::Smallest && channels >= 3) {
    filterRows(raw, h, rowBytes, channels, kPaeth, rows.get());
    if (!literalZlib(rows.get(), filteredSize, idat, 0.75)) idat.clear();
  }
  if (idat.empty()) {
    filterRows(raw, h, rowBytes, channels, kUp, rows.get());
    libdeflate_compressor* c = compressor();
    const std::size_t bound = libdeflate_zlib_compress_bound(c, filteredSize);
    idat.resize(bound);
    idat.resize(libdeflate_zlib_compress(c, rows.get(), filteredSize, idat.data(), bound));
    if (idat.empty()) throw std::runtime_error("PNG export: deflate failed");
  }
  rows.reset();
  packed.reset();
  const std::size_t idatSize = idat.size();
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  png.reserve(idatSize + palette.size() * 4 + 128);
  std::vector<std::uint8_t> ihdr;
  put32(ihdr, static_cast<std::uint32_t>(w));
  put32(ihdr, static_cast<std::uint32_t>(h));
  // bit depth, colour type, deflate, adaptive filtering, no interlace
  ihdr.insert(ihdr.end(), {static_cast<std::uint8_t>(bitDepth), static_cast<std::uint8_t>(colourType), 0, 0, 0});
  chunk(png, "IHDR", ihdr.data(), ihdr.size());
  if (colourType == 3) {
    std::vector<std::uint8_t> plte, trns;
    for (std::uint32_t col : palette) {
      plte.insert(plte.end(), {std::uint8_t(col), std::uint8_t(col >> 8), std::uint8_t(col >> 16)});
      if ((col >> 24) != 255) trns.push_back(std::uint8_t(col >> 24));  // translucent ones come first
    }
    chunk(png, "PLTE", plte.data(), plte.size());
    if (!trns.empty()) chunk(png, "tRNS", trns.data(), trns.size());
  }
  // IDAT chunks of at most 1 MiB (a chunk's length is 31 bits; smaller ones suit streaming readers).
  for (std::size_t at = 0; at < idatSize; at += std::size_t(1) << 20)
    chunk(png, "IDAT", idat.data() + at, std::min<std::size_t>(std::size_t(1) << 20, idatSize - at));
  chunk(png, "IEND", nullptr, 0);
  return png;
}

}  // namespace rover::maps
