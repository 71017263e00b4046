#pragma once
// A streaming MCAP writer (https://mcap.dev/spec, major version 0), written from the specification:
// no C++ MCAP library is packaged in Debian 12. What it writes, in order:
//   magic, Header, [Schema, Channel records as they are added], Chunk records (zstd, each followed
//   by one MessageIndex record per channel it holds), DataEnd (CRC of the data section);
//   summary: every Schema, every Channel, Statistics, one ChunkIndex per chunk;
//   summary offsets: one SummaryOffset per group; Footer (CRC of summary + offsets); magic.
// Schemas and channels are written outside chunks and repeated in the summary, so both a linear
// reader and an indexed one (which reads only the summary) find them.
//
// Memory: one chunk's uncompressed records (about `chunkBytes`; a single larger message makes a
// chunk of its own), its message index entries (16 bytes a message) and, for the whole file, one
// ChunkIndex per chunk and the schema/channel records. Bytes go to the stream as each chunk closes.
// The output is a pure function of the calls (no clock, no randomness): the same calls give the
// same bytes with the same zstd release.
#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rover::exports {

// MCAP record opcodes (spec "Records").
enum class McapOp : std::uint8_t {
  Header = 0x01,
  Footer = 0x02,
  Schema = 0x03,
  Channel = 0x04,
  Message = 0x05,
  Chunk = 0x06,
  MessageIndex = 0x07,
  ChunkIndex = 0x08,
  Statistics = 0x0B,
  SummaryOffset = 0x0E,
  DataEnd = 0x0F,
};

// The 8 magic bytes that open and close every MCAP file: 0x89 "MCAP" '0' "\r\n".
extern const std::string_view kMcapMagic;

struct McapOptions {
  std::string profile;               // Header.profile: "" (no ROS profile: JSON messages)
  std::string library = "roverplan";  // Header.library
  std::size_t chunkBytes = 1 << 20;  // a chunk closes when its uncompressed records pass this
  // ZSTD_compress level. The default team mission (330 262 messages): level 3 writes 15.1 MB in
  // ~1 s of CPU, level 6 14.0 MB in ~2.5 s; the server writes a replay as each mission ends.
  int zstdLevel = 3;
};

struct McapTotals {
  std::uint64_t bytes = 0, messages = 0, chunks = 0;
  std::uint32_t channels = 0;
  std::uint16_t schemas = 0;
};

class McapWriter {
 public:
  // Writes the magic and the Header at once.
  McapWriter(std::ostream& out, McapOptions options = {});
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A schema (ids from 1; 0 means "no schema" in the spec) and a channel on it. Throws
  // std::logic_error after finish() or past 65535 of either.
  std::uint16_t addSchema(const std::string& name, const std::string& encoding, std::string_view data);
  std::uint16_t addChannel(std::uint16_t schemaId, const std::string& topic, const std::string& messageEncoding,
                           const std::map<std::string, std::string>& metadata = {});
  // One message; its sequence number is the channel's count so far. log_time = publish_time is
  // the caller's choice (both given). Messages may come in any time order; a chunk's time range
  // is the span of what it holds.
  void write(std::uint16_t channelId, std::uint64_t logTime, std::uint64_t publishTime, std::string_view data);
  // Closes the last chunk and writes DataEnd, the summary, the summary offsets, the Footer and
  // the closing magic. Throws std::runtime_error when the stream failed.
  McapTotals finish();

 private:
  struct ChunkIndexEntry {
    std::uint64_t start = 0, end = 0, offset = 0, length = 0, indexLength = 0, compressed = 0, uncompressed = 0;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> indexOffsets;  // channel -> MessageIndex offset
  };
  void emit(std::string_view bytes);  // to the stream, counted and CRC'd
  void emitRecord(McapOp op, std::string_view content);
  void flushChunk();

  std::ostream& out_;
  McapOptions options_;
  std::uint64_t position_ = 0;
  std::uint32_t crc_ = 0;  // running CRC-32 of the current section
  bool finished_ = false;
  std::vector<std::string> schemaRecords_, channelRecords_;  // contents, for the summary
  std::map<std::uint16_t, std::uint64_t> channelCounts_;      // messages per channel (ordered: stable bytes)
  std::uint64_t messages_ = 0, firstTime_ = UINT64_MAX, lastTime_ = 0;
  // The open chunk: its uncompressed records, time span, and per channel (log_time, offset).
  std::string chunk_;
  std::uint64_t chunkStart_ = UINT64_MAX, chunkEnd_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunkIndex_;
  std::vector<ChunkIndexEntry> chunks_;
};

// CRC-32 (ISO-HDLC, as zlib's crc32) of `bytes`, continuing from `crc`: the CRC every MCAP field holds.
std::uint32_t mcapCrc32(std::string_view bytes, std::uint32_t crc = 0);

}  // namespace rover::exports
