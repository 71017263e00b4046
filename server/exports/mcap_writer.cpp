#include "server/exports/mcap_writer.hpp"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace rover::exports {

const std::string_view kMcapMagic("\x89MCAP0\r\n", 8);

std::uint32_t mcapCrc32(std::string_view bytes, std::uint32_t crc) {
  // zlib's crc32 takes at most uInt bytes a call.
  while (!bytes.empty()) {
    const std::size_t n = std::min<std::size_t>(bytes.size(), std::numeric_limits<uInt>::max());
    crc = static_cast<std::uint32_t>(::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(n)));
    bytes.remove_prefix(n);
  }
  return crc;
}

namespace {

// The spec's primitive encodings: little-endian integers, strings and byte arrays prefixed by
// their length (uint32), records as <opcode uint8><length uint64><content>.
void putU8(std::string& s, std::uint8_t v) { s.push_back(static_cast<char>(v)); }
template <class T>
void putLe(std::string& s, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) s.push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xFF));
}
void putU16(std::string& s, std::uint16_t v) { putLe(s, v); }
void putU32(std::string& s, std::uint32_t v) { putLe(s, v); }
void putU64(std::string& s, std::uint64_t v) { putLe(s, v); }
void putBytes32(std::string& s, std::string_view v) {
  if (v.size() > std::numeric_limits<std::uint32_t>::max()) throw std::length_error("MCAP: a string or byte array over 4 GiB");
  putU32(s, static_cast<std::uint32_t>(v.size()));
  s.append(v);
}

}  // namespace

McapWriter::McapWriter(std::ostream& out, McapOptions options) : out_(out), options_(std::move(options)) {
  emit(kMcapMagic);
  std::string header;
  putBytes32(header, options_.profile);
  putBytes32(header, options_.library);
  emitRecord(McapOp::Header, header);
}

void McapWriter::emit(std::string_view bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  crc_ = mcapCrc32(bytes, crc_);
  position_ += bytes.size();
}

void McapWriter::emitRecord(McapOp op, std::string_view content) {
  std::string head;
  putU8(head, static_cast<std::uint8_t>(op));
  putU64(head, content.size());
  emit(head);
  emit(content);
}

std::uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding, std::string_view data) {
  if (finished_) throw std::logic_error("MCAP: schema added after finish");
  if (schemaRecords_.size() >= 65535) throw std::logic_error("MCAP: more than 65535 schemas");
  const auto id = static_cast<std::uint16_t>(schemaRecords_.size() + 1);
  std::string r;
  putU16(r, id);
  putBytes32(r, name);
  putBytes32(r, encoding);
  putBytes32(r, data);
  // Outside chunks: close the open one first so the record precedes every message that uses it.
  flushChunk();
  emitRecord(McapOp::Schema, r);
  schemaRecords_.push_back(std::move(r));
  return id;
}

std::uint16_t McapWriter::addChannel(std::uint16_t schemaId, const std::string& topic, const std::string& messageEncoding,
                                     const std::map<std::string, std::string>& metadata) {
  if (finished_) throw std::logic_error("MCAP: channel added after finish");
  if (channelRecords_.size() >= 65535) throw std::logic_error("MCAP: more than 65535 channels");
  if (schemaId > schemaRecords_.size()) throw std::logic_error("MCAP: channel on an unknown schema");
  const auto id = static_cast<std::uint16_t>(channelRecords_.size() + 1);  // ids from 1, as schemas
  std::string r, map;
  putU16(r, id);
  putU16(r, schemaId);
  putBytes32(r, topic);
  putBytes32(r, messageEncoding);
  for (const auto& [k, v] : metadata) {  // std::map: keys in order, the same bytes every run
    putBytes32(map, k);
    putBytes32(map, v);
  }
  putBytes32(r, map);
  flushChunk();
  emitRecord(McapOp::Channel, r);
  channelRecords_.push_back(std::move(r));
  channelCounts_[id];  // a channel without messages is still counted (0) in Statistics
  return id;
}

void McapWriter::write(std::uint16_t channelId, std::uint64_t logTime, std::uint64_t publishTime, std::string_view data) {
  if (finished_) throw std::logic_error("MCAP: message written after finish");
  if (channelId == 0 || channelId > channelRecords_.size()) throw std::logic_error("MCAP: message on an unknown channel");
  std::uint64_t& count = channelCounts_[channelId];
  if (count > std::numeric_limits<std::uint32_t>::max()) throw std::length_error("MCAP: over 2^32 messages on a channel");
  std::string head;
  putU16(head, channelId);
  putU32(head, static_cast<std::uint32_t>(count));
  putU64(head, logTime);
  putU64(head, publishTime);
  // The message index offset is the record's position inside the chunk's uncompressed records.
  chunkIndex_[channelId].emplace_back(logTime, chunk_.size());
  putU8(chunk_, static_cast<std::uint8_t>(McapOp::Message));
  putU64(chunk_, head.size() + data.size());
  chunk_ += head;
  chunk_.append(data);
  ++count;
  ++messages_;
  chunkStart_ = std::min(chunkStart_, logTime);
  chunkEnd_ = std::max(chunkEnd_, logTime);
  firstTime_ = std::min(firstTime_, logTime);
  lastTime_ = std::max(lastTime_, logTime);
  if (chunk_.size() >= options_.chunkBytes) flushChunk();
}

void McapWriter::flushChunk() {
  if (chunk_.empty()) return;
  std::string compressed(ZSTD_compressBound(chunk_.size()), '\0');
  const std::size_t n = ZSTD_compress(compressed.data(), compressed.size(), chunk_.data(), chunk_.size(), options_.zstdLevel);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("MCAP: zstd: ") + ZSTD_getErrorName(n));
  compressed.resize(n);

  ChunkIndexEntry e;
  e.start = chunkStart_;
  e.end = chunkEnd_;
  e.offset = position_;
  e.compressed = compressed.size();
  e.uncompressed = chunk_.size();
  std::string r;
  putU64(r, chunkStart_);
  putU64(r, chunkEnd_);
  putU64(r, chunk_.size());
  putU32(r, mcapCrc32(chunk_));
  putBytes32(r, "zstd");
  putU64(r, compressed.size());  // records: a uint64-prefixed byte array
  r += compressed;
  compressed = std::string();
  emitRecord(McapOp::Chunk, r);
  e.length = position_ - e.offset;
  // One MessageIndex per channel in the chunk, right after it (spec "Message Index").
  const std::uint64_t indexStart = position_;
  for (const auto& [channel, entries] : chunkIndex_) {
    std::string idx, list;
    putU16(idx, channel);
    for (const auto& [time, offset] : entries) {
      putU64(list, time);
      putU64(list, offset);
    }
    putBytes32(idx, list);
    e.indexOffsets.emplace_back(channel, position_);
    emitRecord(McapOp::MessageIndex, idx);
  }
  e.indexLength = position_ - indexStart;
  chunks_.push_back(std::move(e));
  chunk_.clear();
  chunk_.shrink_to_fit();
  chunkIndex_.clear();
  chunkStart_ = UINT64_MAX;
  chunkEnd_ = 0;
}

McapTotals McapWriter::finish() {
  if (finished_) throw std::logic_error("MCAP: finished twice");
  flushChunk();
  finished_ = true;
  // DataEnd holds the CRC of every byte before it, from the leading magic on.
  std::string dataEnd;
  putU32(dataEnd, crc_);
  emitRecord(McapOp::DataEnd, dataEnd);

  // The summary: groups of one record kind each, their offsets recorded for the SummaryOffsets.
  const std::uint64_t summaryStart = position_;
  crc_ = 0;  // the summary CRC runs from here through the Footer's summary_offset_start
  struct Group {
    McapOp op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](McapOp op, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const std::uint64_t start = position_;
    for (const auto& r : records) emitRecord(op, r);
    groups.push_back({op, start, position_ - start});
  };
  group(McapOp::Schema, schemaRecords_);
  group(McapOp::Channel, channelRecords_);

  std::string stats;
  putU64(stats, messages_);
  putU16(stats, static_cast<std::uint16_t>(schemaRecords_.size()));
  putU32(stats, static_cast<std::uint32_t>(channelRecords_.size()));
  putU32(stats, 0);  // attachments
  putU32(stats, 0);  // metadata
  putU32(stats, static_cast<std::uint32_t>(chunks_.size()));
  putU64(stats, messages_ ? firstTime_ : 0);
  putU64(stats, messages_ ? lastTime_ : 0);
  std::string counts;
  for (const auto& [channel, n] : channelCounts_) {
    putU16(counts, channel);
    putU64(counts, n);
  }
  putBytes32(stats, counts);
  group(McapOp::Statistics, {stats});

  std::vector<std::string> indexes;
  indexes.reserve(chunks_.size());
  for (const auto& c : chunks_) {
    std::string r, offsets;
    putU64(r, c.start);
    putU64(r, c.end);
    putU64(r, c.offset);
    putU64(r, c.length);
    for (const auto& [channel, offset] : c.indexOffsets) {
      putU16(offsets, channel);
      putU64(offsets, offset);
    }
    putBytes32(r, offsets);
    putU64(r, c.indexLength);
    putBytes32(r, "zstd");
    putU64(r, c.compressed);
    putU64(r, c.uncompressed);
    indexes.push_back(std::move(r));
  }
  group(McapOp::ChunkIndex, indexes);

  const std::uint64_t offsetsStart = position_;
  for (const Group& g : groups) {
    std::string r;
    putU8(r, static_cast<std::uint8_t>(g.op));
    putU64(r, g.start);
    putU64(r, g.length);
    emitRecord(McapOp::SummaryOffset, r);
  }

  // Footer: its opcode, length and the two offsets are inside the summary CRC, the CRC is not.
  std::string footerHead;
  putU8(footerHead, static_cast<std::uint8_t>(McapOp::Footer));
  putU64(footerHead, 8 + 8 + 4);
  putU64(footerHead, summaryStart);
  putU64(footerHead, offsetsStart);
  emit(footerHead);
  std::string footerCrc;
  putU32(footerCrc, crc_);
  emit(footerCrc);
  emit(kMcapMagic);
  out_.flush();
  if (!out_) throw std::runtime_error("MCAP: the output stream failed");

  McapTotals t;
  t.bytes = position_;
  t.messages = messages_;
  t.chunks = chunks_.size();
  t.channels = static_cast<std::uint32_t>(channelRecords_.size());
  t.schemas = static_cast<std::uint16_t>(schemaRecords_.size());
  return t;
}

}  // namespace rover::exports
