#pragma once
// A zlib stream of literals only: each block of the input is coded with its own Huffman code of
// byte values (deflate's dynamic block, no LZ77 matches), the way fast PNG encoders do (issue 24:
// cold tiles). On a tile whose rows were filtered (PNG's Paeth) the bytes are noise-like residuals
// that LZ77 finds few matches in: most of what deflate gains there is the Huffman code, and the
// match search is most of its time. Not for data with long runs (flat ground, transparent areas):
// literals cost at least a bit a byte where matches cost next to nothing, hence maxCommonest.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rover::maps {

// data[0, n) as a zlib stream (RFC 1950 header, RFC 1951 dynamic blocks of literals, Adler-32)
// appended to `out`, blocks of at most 1 MiB of input each; or false, `out` untouched, when the
// most frequent byte value is more than `maxCommonest` of the bytes (runs: LZ77's case).
bool literalZlib(const std::uint8_t* data, std::size_t n, std::vector<std::uint8_t>& out, double maxCommonest = 1.0);

}  // namespace rover::maps
