#include "maps/literal_deflate.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <memory>
#include <queue>

namespace rover::maps {

namespace {

constexpr std::size_t kBlock = std::size_t(1) << 20;
constexpr int kLiterals = 257;  // byte values and end-of-block (256); no lengths, so HLIT = 257

// Code lengths of a Huffman code for freq (zero: no code), none longer than maxBits: when the
// tree is too deep the counts are halved (rounding up, so no used symbol is lost) and it is built
// again. With two or more used symbols the code is complete, as inflate requires of the
// code-length code; a single used symbol gets length 1.
template <std::size_t N>
std::array<std::uint8_t, N> huffmanLengths(std::array<std::uint32_t, N> freq, int maxBits) {
  std::array<std::uint8_t, N> len{};
  for (;;) {
    using Node = std::pair<std::uint64_t, int>;  // weight, node (leaves 0..N-1, then inner nodes)
    std::priority_queue<Node, std::vector<Node>, std::greater<>> heap;
    std::vector<int> parent(2 * N, -1);
    int used = 0;
    for (std::size_t s = 0; s < N; ++s)
      if (freq[s]) heap.emplace(freq[s], static_cast<int>(s)), ++used;
    len.fill(0);
    if (used == 1) {
      len[heap.top().second] = 1;
      return len;
    }
    int next = static_cast<int>(N);
    while (heap.size() > 1) {
      const Node a = heap.top();
      heap.pop();
      const Node b = heap.top();
      heap.pop();
      parent[a.second] = parent[b.second] = next;
      heap.emplace(a.first + b.first, next++);
    }
    // Inner nodes are numbered after their children, so depths follow from the root down.
    std::vector<int> depth(next, 0);
    for (int v = next - 2; v >= 0; --v)
      if (parent[v] >= 0) depth[v] = depth[parent[v]] + 1;
    int deepest = 0;
    for (std::size_t s = 0; s < N; ++s)
      if (freq[s]) deepest = std::max(deepest, int(len[s] = static_cast<std::uint8_t>(depth[s])));
    if (deepest <= maxBits) return len;
    for (auto& f : freq) f = (f + 1) / 2;
  }
}

// Canonical codes (RFC 1951 3.2.2) for `len`, bit-reversed: deflate sends a code's bits from the
// most significant one into a stream filled from each byte's least significant bit.
template <std::size_t N>
std::array<std::uint16_t, N> canonicalCodes(const std::array<std::uint8_t, N>& len) {
  std::array<int, 16> count{}, next{};
  for (auto l : len) ++count[l];
  count[0] = 0;
  for (int bits = 1, code = 0; bits < 16; ++bits) next[bits] = code = (code + count[bits - 1]) << 1;
  std::array<std::uint16_t, N> codes{};
  for (std::size_t s = 0; s < N; ++s) {
    if (!len[s]) continue;
    unsigned c = next[len[s]]++, r = 0;
    for (int b = 0; b < len[s]; ++b, c >>= 1) r = (r << 1) | (c & 1);
    codes[s] = static_cast<std::uint16_t>(r);
  }
  return codes;
}

// Bits into bytes, least significant first. Each put stores eight bytes and moves on by the whole
// bytes written (no branch a code: a mispredicted one every few codes cost more than the store),
// so the buffer needs 8 bytes beyond the stream's end.
class BitWriter {
  static_assert(std::endian::native == std::endian::little, "put() stores the accumulator as it is in memory");

 public:
  explicit BitWriter(std::uint8_t* out) : out_(out) {}
  void put(std::uint64_t bits, int n) {  // n <= 56
    acc_ |= bits << count_;
    count_ += n;
    std::memcpy(out_, &acc_, 8);  // little-endian: the oldest bits first
    const int whole = count_ >> 3;  // at most 7: fewer than 8 bits were pending, n ≤ 56 came
    out_ += whole;
    acc_ >>= 8 * whole;
    count_ &= 7;
  }
  std::uint8_t* finish() {  // pads the last byte with zeros
    if (count_ > 0) *out_++ = static_cast<std::uint8_t>(acc_);
    count_ = 0;
    acc_ = 0;
    return out_;
  }

 private:
  std::uint8_t* out_;
  std::uint64_t acc_ = 0;
  int count_ = 0;
};

void literalBlock(BitWriter& w, const std::uint8_t* data, std::size_t n, const std::array<std::uint32_t, 256>& hist,
                  bool last) {
  std::array<std::uint32_t, kLiterals> freq{};
  std::copy(hist.begin(), hist.end(), freq.begin());
  freq[256] = 1;
  const auto len = huffmanLengths(freq, 15);
  const auto code = canonicalCodes(len);
  // The code lengths (257 literal ones, then one distance code of zero bits: no matches), each
  // sent in the code-length code of 19 symbols; runs (16-18) are not worth it on 258 symbols.
  std::array<std::uint32_t, 19> clFreq{};
  for (auto l : len) ++clFreq[l];
  ++clFreq[0];
  const auto clLen = huffmanLengths(clFreq, 7);
  const auto clCode = canonicalCodes(clLen);
  static constexpr int kOrder[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
  int sent = 19;
  while (sent > 4 && clLen[kOrder[sent - 1]] == 0) --sent;
  w.put(last ? 1 : 0, 1);
  w.put(2, 2);           // dynamic Huffman codes
  w.put(0, 5);           // HLIT: 257 literal/length codes
  w.put(0, 5);           // HDIST: 1 distance code
  w.put(sent - 4, 4);    // HCLEN
  for (int i = 0; i < sent; ++i) w.put(clLen[kOrder[i]], 3);
  for (auto l : len) w.put(clCode[l], clLen[l]);
  w.put(clCode[0], clLen[0]);  // the distance code's length: 0
  // Each byte's code and length in one word (one load a byte), then as many codes a put as fit
  // its 56 bits: four when no code is longer than 14 bits (most residual tiles), else three. The
  // bits are the same either way.
  std::array<std::uint32_t, 256> entry;
  int longest = 0;
  for (int v = 0; v < 256; ++v) {
    entry[v] = code[v] | std::uint32_t(len[v]) << 16;
    longest = std::max<int>(longest, len[v]);
  }
  auto bitsOf = [&](std::uint32_t e) { return std::uint64_t(e & 0xffffu); };
  auto lenOf = [](std::uint32_t e) { return int(e >> 16); };
  std::size_t i = 0;
  if (longest <= 14) {
    for (; i + 4 <= n; i += 4) {
      const std::uint32_t a = entry[data[i]], b = entry[data[i + 1]], c = entry[data[i + 2]], d = entry[data[i + 3]];
      const int la = lenOf(a), lb = lenOf(b), lc = lenOf(c), ld = lenOf(d);
      w.put(bitsOf(a) | bitsOf(b) << la | bitsOf(c) << (la + lb) | bitsOf(d) << (la + lb + lc), la + lb + lc + ld);
    }
  }
  for (; i + 3 <= n; i += 3) {  // three codes of at most 15 bits
    const std::uint32_t a = entry[data[i]], b = entry[data[i + 1]], c = entry[data[i + 2]];
    const int la = lenOf(a), lb = lenOf(b), lc = lenOf(c);
    w.put(bitsOf(a) | bitsOf(b) << la | bitsOf(c) << (la + lb), la + lb + lc);
  }
  for (; i < n; ++i) w.put(bitsOf(entry[data[i]]), lenOf(entry[data[i]]));
  w.put(code[256], len[256]);
}

}  // namespace

bool literalZlib(const std::uint8_t* data, std::size_t n, std::vector<std::uint8_t>& out, double maxCommonest) {
  // Byte counts per block, four tables interleaved so consecutive equal bytes do not wait on one
  // another's increment.
  const std::size_t blocks = std::max<std::size_t>(1, (n + kBlock - 1) / kBlock);
  std::vector<std::array<std::uint32_t, 256>> hist(blocks);
  std::array<std::uint64_t, 256> total{};
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::uint8_t* p = data + b * kBlock;
    const std::size_t m = std::min(kBlock, n - std::min(n, b * kBlock));
    std::array<std::array<std::uint32_t, 256>, 4> h{};
    std::size_t i = 0;
    for (; i + 4 <= m; i += 4) ++h[0][p[i]], ++h[1][p[i + 1]], ++h[2][p[i + 2]], ++h[3][p[i + 3]];
    for (; i < m; ++i) ++h[0][p[i]];
    for (int v = 0; v < 256; ++v) total[v] += hist[b][v] = h[0][v] + h[1][v] + h[2][v] + h[3][v];
  }
  if (n > 0 && double(*std::max_element(total.begin(), total.end())) > maxCommonest * double(n)) return false;
  // At most 15 bits a byte, a block's header under 300 bytes, the zlib header and Adler-32, and the
  // BitWriter's 8 bytes of slack.
  // (Written into a buffer without std::vector's zero-fill, then appended.)
  std::unique_ptr<std::uint8_t[]> buffer(new std::uint8_t[n / 8 * 15 + 16 + 300 * blocks + 16]);
  buffer[0] = 0x78;  // deflate, 32 KiB window
  buffer[1] = 0x01;  // fastest; (0x78 << 8 | 0x01) is a multiple of 31
  BitWriter w(buffer.get() + 2);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t at = b * kBlock, m = std::min(kBlock, n - std::min(n, at));
    literalBlock(w, data + at, m, hist[b], b + 1 == blocks);
  }
  std::uint8_t* end = w.finish();
  const std::uint32_t adler = libdeflate_adler32(1, data, n);
  for (int i = 3; i >= 0; --i) *end++ = static_cast<std::uint8_t>(adler >> (8 * i));
  out.insert(out.end(), buffer.get(), end);
  return true;
}

}  // namespace rover::maps
