// MissionStream's fan-out (issue 22 item 2), without sockets: subscribers standing at the same cut
// are handed the very same encoded bytes (one shared buffer, one encode), a subscriber that fell
// behind gets one coalesced batch that leaves it where the others are, and every subscriber ends
// on the done frame. The end of a mission forces a cut, so nothing here waits for a clock.
#include <doctest/doctest.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/missions/mission_stream.hpp"

using namespace rover;
using nlohmann::json;

namespace {

struct NoWake : http::WsConnection {
  void wake() override {}
};

// Every frame `source` has now, until it says "nothing now" (or hands out the last frame).
std::vector<http::WsFrame> drain(http::WsSource& source) {
  std::vector<http::WsFrame> out;
  for (int i = 0; i < 100; ++i) {
    auto f = source.next();
    if (!f) break;
    out.push_back(std::move(*f));
    if (out.back().last) break;
  }
  return out;
}

// Two rovers on a 20×20 grid: two cells, both poses and a progress report a step.
void plannerSteps(missions::MissionStream& s, std::int64_t step) {
  const std::vector<CellUpdate> cells{{static_cast<std::int32_t>(step % 12), 1, 1}, {5, 2, 3}};
  s.cellsChanged(cells);
  const std::vector<RoverPose> poses{{0, 1.0 * step, 0.5, 0.0}, {1, 2.0, 0.5 * step, 1.0}};
  s.roverPoses(step, poses);
  Progress p;
  p.step = step;
  p.fraction = 0.1 * static_cast<double>(step);
  s.progress(p);
}

}  // namespace

TEST_CASE("mission stream: subscribers at the same cut get the same shared bytes, encoded once") {
  GridGeometry g;
  g.rows = 20;
  g.cols = 20;
  auto stream = std::make_shared<missions::MissionStream>("m1", g, 2);
  stream->setStatus(RunStatus::Running);
  plannerSteps(*stream, 1);
  auto a = stream->subscribe(std::make_shared<NoWake>());
  auto b = stream->subscribe(std::make_shared<NoWake>());
  const auto snapA = drain(*a), snapB = drain(*b);
  REQUIRE(snapA.size() == 2);  // snapshot, full grid; then nothing new
  REQUIRE(snapB.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    REQUIRE(snapA[i].shared);
    CHECK(snapA[i].shared == snapB[i].shared);  // one buffer, not two equal copies
  }
  CHECK(stream->snapshotBuilds() == 1);

  for (std::int64_t step = 2; step <= 4; ++step) plannerSteps(*stream, step);
  stream->finish(RunStatus::Succeeded, "", json{{"coverage", 0.5}});
  const std::uint64_t encodesBefore = stream->frameEncodes();
  const auto restA = drain(*a);
  const std::uint64_t encodesForA = stream->frameEncodes() - encodesBefore;
  const auto restB = drain(*b);
  CHECK(stream->frameEncodes() - encodesBefore == encodesForA);  // b encoded nothing
  REQUIRE(restA.size() == restB.size());
  REQUIRE(restA.size() == 4);  // grid diff, poses, progress, done
  for (std::size_t i = 0; i < restA.size(); ++i) {
    REQUIRE(restA[i].shared);
    CHECK(restA[i].shared == restB[i].shared);
  }
  CHECK(restA[0].binary);
  const json poses = json::parse(restA[1].bytes());
  CHECK(poses["type"] == "poses");
  CHECK(poses["step"] == 4);
  CHECK(poses["rovers"][0]["append"].size() == 3);  // steps 2, 3, 4 (step 1 was in the snapshot)
  CHECK(json::parse(restA[2].bytes())["type"] == "progress");
  CHECK(json::parse(restA[2].bytes())["step"] == 4);
  CHECK(restA[3].last);
  CHECK(json::parse(restA[3].bytes())["type"] == "done");
  CHECK_FALSE(a->next());
}

TEST_CASE("mission stream: a subscriber that fell behind catches up in one coalesced batch") {
  GridGeometry g;
  g.rows = 20;
  g.cols = 20;
  auto stream = std::make_shared<missions::MissionStream>("m2", g, 2);
  stream->setStatus(RunStatus::Running);
  auto slow = stream->subscribe(std::make_shared<NoWake>());
  REQUIRE(drain(*slow).size() == 2);  // snapshot and grid at the first cut
  for (std::int64_t step = 1; step <= 50; ++step) plannerSteps(*stream, step);
  stream->finish(RunStatus::Succeeded, "", nullptr);
  const auto frames = drain(*slow);
  // One overlay-free batch (grid diff, poses with all 50 points, progress), then done: the 50
  // steps are not replayed one by one.
  REQUIRE(frames.size() == 4);
  const json poses = json::parse(frames[1].bytes());
  CHECK(poses["rovers"][0]["append"].size() == 50);
  CHECK(poses["rovers"][0]["pose"]["x"] == 50.0);
  // The grid diff carries each changed cell once, at its last state.
  const std::string& diff = frames[0].bytes();
  REQUIRE(diff.size() >= 16);
  const auto u32 = [&](std::size_t at) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(diff[at])) |
           static_cast<std::uint32_t>(static_cast<unsigned char>(diff[at + 1])) << 8 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(diff[at + 2])) << 16 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(diff[at + 3])) << 24;
  };
  CHECK(u32(0) == 1);   // cell updates
  CHECK(u32(12) == 12);  // the 12 cells that changed (100 changes), each sent once
  CHECK(diff.size() == 16 + 12 * 12);
  CHECK(frames[3].last);
}
