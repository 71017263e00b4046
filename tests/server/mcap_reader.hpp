#pragma once
// A tiny MCAP reader for the tests (https://mcap.dev/spec), written apart from the writer it checks
// (server/exports/mcap_writer.cpp): its own CRC-32 (bit by bit), its own field decoding. It walks
// the file record by record, checks every CRC and every offset the index gives, and decodes the
// chunks (zstd) into messages. Any departure from the spec fails a REQUIRE.
#include <doctest/doctest.h>
#include <zstd.h>

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace rover::test {

// CRC-32/ISO-HDLC (reflected 0xEDB88320), one bit at a time: slow, and obviously the standard.
inline std::uint32_t bitwiseCrc32(std::string_view bytes) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

struct McapCursor {
  std::string_view s;
  std::size_t at = 0;
  template <class T>
  T le() {
    REQUIRE(at + sizeof(T) <= s.size());
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(s[at + i])) << (8 * i);
    at += sizeof(T);
    return static_cast<T>(v);
  }
  std::string_view bytes(std::size_t n) {
    REQUIRE(at + n <= s.size());
    std::string_view v = s.substr(at, n);
    at += n;
    return v;
  }
  std::string str() { return std::string(bytes(le<std::uint32_t>())); }
  bool done() const { return at == s.size(); }
};

struct McapRecord {
  std::uint8_t op;
  std::size_t offset;  // of the opcode, from the file start
  std::string_view content;
};

struct McapMessage {
  std::uint16_t channel;
  std::uint32_t sequence;
  std::uint64_t logTime, publishTime;
  std::string data;
};

struct McapChannel {
  std::uint16_t schema;
  std::string topic, encoding;
};

struct McapSchema {
  std::string name, encoding, data;
};

struct McapFile {
  std::vector<McapRecord> records;  // the top level, in file order
  std::map<std::uint16_t, McapSchema> schemas;
  std::map<std::uint16_t, McapChannel> channels;
  std::vector<McapMessage> messages;  // in file order
  std::uint64_t statsMessages = 0;
  std::uint32_t statsChunks = 0, statsChannels = 0;
  std::map<std::uint16_t, std::uint64_t> statsPerChannel;

  std::size_t count(const std::string& topic) const {
    std::size_t n = 0;
    for (const auto& m : messages) n += channels.at(m.channel).topic == topic;
    return n;
  }
};

inline std::vector<McapRecord> mcapRecords(std::string_view file, std::size_t from, std::size_t to) {
  std::vector<McapRecord> out;
  McapCursor c{file.substr(0, to), from};
  while (c.at < to) {
    const std::size_t offset = c.at;
    const auto op = c.le<std::uint8_t>();
    const auto len = c.le<std::uint64_t>();
    out.push_back({op, offset, c.bytes(static_cast<std::size_t>(len))});
  }
  return out;
}

// Reads and checks a whole file (magic, sections, CRCs, indexes, statistics).
inline McapFile readMcap(std::string_view file) {
  const std::string_view magic("\x89MCAP0\r\n", 8);
  REQUIRE(file.size() >= 8 + 9 + 20 + 8);
  REQUIRE(file.substr(0, 8) == magic);
  REQUIRE(file.substr(file.size() - 8) == magic);
  // The Footer: 9 bytes of opcode and length + 20 of content, before the closing magic.
  const std::size_t footerAt = file.size() - 8 - 29;
  McapCursor f{file, footerAt};
  REQUIRE(f.le<std::uint8_t>() == 0x02);
  REQUIRE(f.le<std::uint64_t>() == 20);
  const auto summaryStart = f.le<std::uint64_t>(), offsetsStart = f.le<std::uint64_t>();
  const auto summaryCrc = f.le<std::uint32_t>();
  REQUIRE(summaryStart > 0);
  CHECK(summaryCrc == bitwiseCrc32(file.substr(summaryStart, footerAt + 1 + 8 + 16 - summaryStart)));

  McapFile out;
  out.records = mcapRecords(file, 8, footerAt);
  REQUIRE(!out.records.empty());
  CHECK(out.records.front().op == 0x01);  // Header first
  std::map<std::size_t, const McapRecord*> at;
  for (const auto& r : out.records) at[r.offset] = &r;
  bool dataEnded = false;
  for (const auto& r : out.records) {
    McapCursor c{r.content};
    if (r.offset >= summaryStart) break;
    CHECK_FALSE(dataEnded);
    if (r.op == 0x0F) {  // DataEnd: CRC of everything before it
      CHECK(c.le<std::uint32_t>() == bitwiseCrc32(file.substr(0, r.offset)));
      CHECK(r.offset + 9 + 4 == summaryStart);
      dataEnded = true;
    } else if (r.op == 0x03) {
      const auto id = c.le<std::uint16_t>();
      McapSchema s{c.str(), c.str(), c.str()};
      out.schemas[id] = s;
    } else if (r.op == 0x04) {
      const auto id = c.le<std::uint16_t>();
      McapChannel ch;
      ch.schema = c.le<std::uint16_t>();
      ch.topic = c.str();
      ch.encoding = c.str();
      c.bytes(c.le<std::uint32_t>());  // metadata
      CHECK(c.done());
      CHECK((ch.schema == 0 || out.schemas.count(ch.schema) == 1));
      out.channels[id] = ch;
    } else if (r.op == 0x06) {
      c.le<std::uint64_t>();
      c.le<std::uint64_t>();
      const auto size = c.le<std::uint64_t>();
      const auto crc = c.le<std::uint32_t>();
      REQUIRE(c.str() == "zstd");
      const std::string_view packed = c.bytes(static_cast<std::size_t>(c.le<std::uint64_t>()));
      CHECK(c.done());
      std::string records(static_cast<std::size_t>(size), '\0');
      REQUIRE(ZSTD_decompress(records.data(), records.size(), packed.data(), packed.size()) == size);
      CHECK(crc == bitwiseCrc32(records));
      for (const auto& m : mcapRecords(records, 0, records.size())) {
        REQUIRE(m.op == 0x05);
        McapCursor mc{m.content};
        McapMessage msg;
        msg.channel = mc.le<std::uint16_t>();
        msg.sequence = mc.le<std::uint32_t>();
        msg.logTime = mc.le<std::uint64_t>();
        msg.publishTime = mc.le<std::uint64_t>();
        msg.data = std::string(m.content.substr(mc.at));
        REQUIRE(out.channels.count(msg.channel) == 1);
        out.messages.push_back(std::move(msg));
      }
    }
  }
  CHECK(dataEnded);
  // The summary: Statistics and one ChunkIndex per chunk, every offset pointing where it says.
  std::size_t chunksSeen = 0;
  for (const auto& r : out.records) {
    if (r.offset < summaryStart) {
      chunksSeen += r.op == 0x06;
      continue;
    }
    McapCursor c{r.content};
    if (r.op == 0x0B) {
      out.statsMessages = c.le<std::uint64_t>();
      c.le<std::uint16_t>();
      out.statsChannels = c.le<std::uint32_t>();
      CHECK(c.le<std::uint32_t>() == 0);
      CHECK(c.le<std::uint32_t>() == 0);
      out.statsChunks = c.le<std::uint32_t>();
      c.le<std::uint64_t>();
      c.le<std::uint64_t>();
      McapCursor m{c.bytes(c.le<std::uint32_t>())};
      while (!m.done()) {
        const auto ch = m.le<std::uint16_t>();
        out.statsPerChannel[ch] = m.le<std::uint64_t>();
      }
    } else if (r.op == 0x08) {
      c.le<std::uint64_t>();
      c.le<std::uint64_t>();
      const auto chunkAt = c.le<std::uint64_t>(), chunkLength = c.le<std::uint64_t>();
      REQUIRE(at.count(chunkAt) == 1);
      CHECK(at[chunkAt]->op == 0x06);
      CHECK(at[chunkAt]->content.size() + 9 == chunkLength);
      McapCursor m{c.bytes(c.le<std::uint32_t>())};
      while (!m.done()) {
        m.le<std::uint16_t>();
        const auto indexAt = m.le<std::uint64_t>();
        REQUIRE(at.count(indexAt) == 1);
        CHECK(at[indexAt]->op == 0x07);
      }
    } else if (r.op == 0x0E) {
      CHECK(r.offset >= offsetsStart);
      const auto group = c.le<std::uint8_t>();
      const auto start = c.le<std::uint64_t>();
      REQUIRE(at.count(start) == 1);
      CHECK(at[start]->op == group);
    }
  }
  CHECK(out.statsChunks == chunksSeen);
  CHECK(out.statsMessages == out.messages.size());
  CHECK(out.statsChannels == out.channels.size());
  return out;
}

}  // namespace rover::test
