// The MCAP writer (server/exports/mcap_writer) and the mission replay it carries
// (server/exports/mission_mcap), read back by the tests' own reader (mcap_reader.hpp).
#include <doctest/doctest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "mcap_reader.hpp"
#include "server/exports/mcap_writer.hpp"
#include "server/exports/mission_mcap.hpp"

using namespace rover;
using rover::exports::McapOptions;
using rover::exports::McapWriter;
using rover::test::bitwiseCrc32;
using rover::test::readMcap;
using nlohmann::json;

namespace {

std::string tinyFile(McapOptions o = {}) {
  std::ostringstream out;
  McapWriter w(out, o);
  const auto s = w.addSchema("t.Point", "jsonschema", "{}");
  const auto a = w.addChannel(s, "/a", "json", {{"k", "v"}});
  const auto b = w.addChannel(s, "/b", "json");
  w.write(a, 1000, 1000, "{\"x\":1}");
  w.write(b, 1500, 1500, "{\"x\":2}");
  w.write(a, 2000, 2000, "{\"x\":3}");
  w.finish();
  return out.str();
}

}  // namespace

TEST_CASE("mcap writer: CRC-32 is the standard one (check value of 123456789)") {
  CHECK(exports::mcapCrc32("123456789") == 0xCBF43926u);
  CHECK(bitwiseCrc32("123456789") == 0xCBF43926u);
  CHECK(exports::mcapCrc32("89", exports::mcapCrc32("1234567")) == 0xCBF43926u);  // continued
}

TEST_CASE("mcap writer: a literal tiny file, record by record") {
  const std::string f = tinyFile();
  // Magic, then the Header record: opcode 0x01, length 4 + 0 + 4 + 9, profile "", library "roverplan".
  const std::string head = std::string("\x89MCAP0\r\n", 8) + '\x01' + std::string("\x11\0\0\0\0\0\0\0", 8) +
                           std::string("\0\0\0\0", 4) + std::string("\x09\0\0\0", 4) + "roverplan";
  CHECK(f.substr(0, head.size()) == head);
  // The Schema record right after: id 1, name, encoding, data.
  const std::string schema = std::string("\x03", 1) + std::string("\x21\0\0\0\0\0\0\0", 8) + std::string("\x01\0", 2) +
                             std::string("\x07\0\0\0", 4) + "t.Point" + std::string("\x0a\0\0\0", 4) + "jsonschema" +
                             std::string("\x02\0\0\0", 4) + "{}";
  CHECK(f.substr(head.size(), schema.size()) == schema);

  const test::McapFile m = readMcap(f);
  std::vector<int> ops;
  for (const auto& r : m.records) ops.push_back(r.op);
  // Header, Schema, Channel ×2, Chunk, MessageIndex ×2, DataEnd | Schema, Channel ×2, Statistics,
  // ChunkIndex | SummaryOffset ×4 (one per group).
  CHECK(ops == std::vector<int>{0x01, 0x03, 0x04, 0x04, 0x06, 0x07, 0x07, 0x0F, 0x03, 0x04, 0x04, 0x0B, 0x08, 0x0E, 0x0E, 0x0E, 0x0E});
  REQUIRE(m.messages.size() == 3);
  CHECK(m.channels.at(1).topic == "/a");
  CHECK(m.channels.at(2).topic == "/b");
  CHECK(m.schemas.at(1).encoding == "jsonschema");
  CHECK(m.messages[0].channel == 1);
  CHECK(m.messages[0].sequence == 0);
  CHECK(m.messages[2].sequence == 1);  // the channel's second message
  CHECK(m.messages[1].logTime == 1500);
  CHECK(m.messages[2].data == "{\"x\":3}");
  CHECK(m.statsPerChannel.at(1) == 2);
  CHECK(m.statsPerChannel.at(2) == 1);
  // The Chunk's header: its time span, then the uncompressed size and "zstd".
  const auto& chunk = m.records[4];
  test::McapCursor c{chunk.content};
  CHECK(c.le<std::uint64_t>() == 1000);
  CHECK(c.le<std::uint64_t>() == 2000);
  // A MessageIndex lists (log_time, offset in the uncompressed records): channel 1's second
  // message follows two message records of 9 + 22 + 7 bytes.
  test::McapCursor idx{m.records[5].content};
  CHECK(idx.le<std::uint16_t>() == 1);
  CHECK(idx.le<std::uint32_t>() == 32);
  CHECK(idx.le<std::uint64_t>() == 1000);
  CHECK(idx.le<std::uint64_t>() == 0);
  CHECK(idx.le<std::uint64_t>() == 2000);
  CHECK(idx.le<std::uint64_t>() == 2 * (9 + 22 + 7));
}

TEST_CASE("mcap writer: the same calls give the same bytes, small chunks split and stay indexed") {
  CHECK(tinyFile() == tinyFile());
  McapOptions small;
  small.chunkBytes = 1;  // every message closes its chunk
  const std::string f = tinyFile(small);
  const test::McapFile m = readMcap(f);
  CHECK(m.statsChunks == 3);
  CHECK(m.messages.size() == 3);
  std::size_t indexes = 0;
  for (const auto& r : m.records) indexes += r.op == 0x08;
  CHECK(indexes == 3);
}

TEST_CASE("mcap writer: misuse is refused") {
  std::ostringstream out;
  McapWriter w(out);
  CHECK_THROWS_AS(w.addChannel(3, "/x", "json"), std::logic_error);  // no such schema
  CHECK_THROWS_AS(w.write(1, 0, 0, "{}"), std::logic_error);        // no such channel
  w.finish();
  CHECK_THROWS_AS(w.addSchema("s", "jsonschema", "{}"), std::logic_error);
  const test::McapFile m = readMcap(out.str());  // an empty file is still a valid one
  CHECK(m.messages.empty());
}

TEST_CASE("mission replay: the terrain grid is at most 2^20 cells") {
  CHECK(exports::terrainStride(600, 600) == 1);
  CHECK(exports::terrainStride(1024, 1024) == 1);
  CHECK(exports::terrainStride(1025, 1024) == 2);
  CHECK(exports::terrainStride(4000, 3000) == 4);  // 1000 × 750
}

TEST_CASE("mission replay: channels and messages from a literal two-rover result on a 3 × 4 DEM") {
  // The DEM (1 m cells), heights by row from the north: row 0 = 3 m ... row 2 = 1 m, one nodata.
  //   3 3 3 3
  //   2 2 N 2
  //   1 1 1 1
  terrain::Dem dem;
  dem.z = Raster<float>(GridGeometry{3, 4, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) dem.z(r, c) = static_cast<float>(3 - r);
  dem.z(1, 2) = std::numeric_limits<float>::quiet_NaN();

  PlanResult result;
  result.planner = "team";
  for (int k = 0; k < 2; ++k) {
    Track t;
    t.rover = k;
    for (int i = 0; i < 3 + k; ++i) {
      TrackSample s;
      s.time = 0.1 * i;
      s.position = {0.5 + 0.1 * i, 0.5 + k};
      s.heading = std::numbers::pi / 2;
      s.roll = 0.01;
      s.pitch = -0.02;
      s.speed = 0.3;
      s.elevation = 1.0;
      t.samples.push_back(s);
      t.points.push_back(s.position);
    }
    result.tracks.push_back(t);
  }
  result.overlays.push_back({"route", -1, {{0.5, 0.5}, {3.5, 2.5}}});
  result.overlays.push_back({"path", 0, {{0.5, 0.5}, {0.7, 0.5}}});
  result.targets.push_back({0, {3.5, 2.5}, TargetStatus::Reached, 2, 0, 0, 0});
  result.incidents.push_back({IncidentKind::Collision, 1, 0, 0.15, {0.6, 1.0}, 0.4, "rovers 0 and 1 within 0.40 m", -1, "safety_distance"});
  result.series.push_back({"energy_j_rover_0", "time (s)", "energy_j", {0.0, 0.2}, {0.0, 2.0}});

  exports::ReplayInput in;
  in.result = &result;
  in.dem = &dem;
  in.grid = dem.geometry();
  maps::Zone crater;
  crater.rings = {{Eigen::Vector2d(1, 1), Eigen::Vector2d(2, 1), Eigen::Vector2d(2, 2)}};
  crater.name = "crater";
  in.zones = {crater};
  std::ostringstream out;
  const exports::McapTotals totals = exports::writeReplayMcap(in, out);
  const std::string bytes = out.str();
  CHECK(totals.bytes == bytes.size());
  const test::McapFile m = readMcap(bytes);

  // No CRS: no fixes. Terrain, scene, incidents, then pose + telemetry per rover.
  std::vector<std::string> topics;
  for (const auto& [id, ch] : m.channels) topics.push_back(ch.topic);
  CHECK(topics == std::vector<std::string>{"/map/terrain", "/map/scene", "/incidents", "/rover_0/pose", "/rover_0/telemetry",
                                           "/rover_1/pose", "/rover_1/telemetry"});
  CHECK(m.schemas.at(m.channels.at(4).schema).name == "foxglove.PoseInFrame");
  CHECK(m.count("/rover_0/pose") == 3);
  CHECK(m.count("/rover_1/pose") == 4);
  CHECK(m.count("/rover_1/telemetry") == 4);
  CHECK(m.count("/incidents") == 1);
  CHECK(m.messages.size() == 2 + 1 + 2 * 7);
  for (std::size_t i = 1; i < m.messages.size(); ++i) CHECK(m.messages[i - 1].logTime <= m.messages[i].logTime);

  for (const auto& msg : m.messages) {
    const json j = json::parse(msg.data);  // every message is JSON
    const std::string& topic = m.channels.at(msg.channel).topic;
    if (topic == "/map/terrain") {
      CHECK(j["column_count"] == 4);
      CHECK(j["row_stride"] == 16);
      CHECK(j["fields"][0]["type"] == 7);
      CHECK(j["data"].get<std::string>().size() == 4 * ((48 + 2) / 3));  // 12 float32, base64
      // Row 0 of the grid is the south edge (1 m); the nodata cell is in its second row.
      CHECK(j["data"].get<std::string>().substr(0, 8) == "AACAPwAA");  // 1.0f = 00 00 80 3f
    } else if (topic == "/map/scene") {
      std::vector<std::string> ids;
      for (const auto& e : j["entities"]) ids.push_back(e["id"]);
      CHECK(ids == std::vector<std::string>{"route", "path_rover_0", "targets", "zone_0"});
      CHECK(j["entities"][3]["lines"][0]["type"] == 1);  // LINE_LOOP
    } else if (topic == "/incidents") {
      CHECK(msg.logTime == 150000000);
      CHECK(j["level"] == 4);
      CHECK(j["name"] == "rover_1");
    } else if (topic == "/rover_0/pose" && msg.sequence == 2) {
      CHECK(msg.logTime == 200000000);
      CHECK(msg.publishTime == msg.logTime);
      CHECK(j["timestamp"]["nsec"] == 200000000);
      CHECK(j["pose"]["position"]["x"].get<double>() == doctest::Approx(0.7));
      CHECK(j["pose"]["orientation"]["z"].get<double>() == doctest::Approx(std::sqrt(0.5)).epsilon(1e-6));
    } else if (topic == "/rover_0/telemetry" && msg.sequence == 1) {
      CHECK(j["energy_j"].get<double>() == doctest::Approx(1.0));  // halfway along the series
      CHECK(j["pitch_deg"].get<double>() == doctest::Approx(-0.02 * 180 / std::numbers::pi).epsilon(1e-3));
      CHECK(j["speed_m_s"].get<double>() == doctest::Approx(0.3));
    } else if (topic == "/rover_1/telemetry") {
      CHECK_FALSE(j.contains("energy_j"));  // no series for rover 1: left out
    }
  }
  // A pure function of its inputs.
  std::ostringstream again;
  exports::writeReplayMcap(in, again);
  CHECK(again.str() == bytes);
}
