// The generic stream (server/streams/channel_stream.hpp, issue 23 item 4) without sockets: a toy
// stream of two named logs shows the batch order, the sharing at a cut and the end; the study
// stream, built on it, keeps its frames (snapshot, progress with the summary only when it
// changed, done last). Every change here is a forced cut, so nothing waits for a clock.
#include <doctest/doctest.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/streams/channel_stream.hpp"
#include "server/studies/study_stream.hpp"

using namespace rover;
using nlohmann::json;

namespace {

struct NoWake : http::WsConnection {
  void wake() override {}
};

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

// An append-only log of words: a frame "name:word word" of the words a reader has not seen.
class WordLog : public streams::Channel {
 public:
  using Channel::Channel;
  std::vector<std::string> words;
  streams::Position position() const override { return {words.size()}; }
  std::size_t frames(const streams::Position& from, const streams::Position& to, streams::Batch& out) override {
    std::string text = name() + ":";
    for (std::size_t i = streams::lengthAt(from, 0); i < streams::lengthAt(to, 0); ++i) text += " " + words[i];
    if (streams::lengthAt(from, 0) == streams::lengthAt(to, 0)) return 0;
    out.emplace_back(false, std::make_shared<const std::string>(text), false);
    return 1;
  }
};

class TwoLogs : public streams::ChannelStream {
 public:
  TwoLogs() : ChannelStream({std::chrono::milliseconds(0), std::chrono::milliseconds(0), std::chrono::milliseconds(0)}) {
    addChannel(first_);
    addChannel(second_);
  }
  void add(bool toSecond, const std::string& word) {
    {
      std::lock_guard lock(mutex_);
      (toSecond ? second_ : first_).words.push_back(word);
      changedLocked();
    }
    wakeAll(true);
  }
  void end() {
    {
      std::lock_guard lock(mutex_);
      ended_ = true;
      changedLocked();
    }
    wakeAll(true);
  }

 private:
  std::function<streams::Batch()> captureSnapshotLocked() override {
    return [n = first_.words.size() + second_.words.size()] {
      return streams::Batch{http::WsFrame{false, "snapshot " + std::to_string(n)}};
    };
  }
  bool endedLocked() const override { return ended_; }
  std::shared_ptr<const std::string> doneFrameLocked() override {
    return std::make_shared<const std::string>("done");
  }
  WordLog first_{"first"}, second_{"second"};
  bool ended_ = false;
};

}  // namespace

TEST_CASE("channel stream: a batch holds each channel's new entries in channel order, shared at a cut") {
  auto stream = std::make_shared<TwoLogs>();
  stream->add(false, "a");
  auto x = stream->subscribe(std::make_shared<NoWake>());
  auto y = stream->subscribe(std::make_shared<NoWake>());
  const auto snapX = drain(*x), snapY = drain(*y);
  REQUIRE(snapX.size() == 1);
  CHECK(snapX[0].bytes() == "snapshot 1");
  CHECK(snapY[0].bytes() == "snapshot 1");
  CHECK(stream->snapshotBuilds() == 1);  // y joined at the same state: the same snapshot

  stream->add(true, "b");   // the second channel first ...
  stream->add(false, "c");  // ... then the first: the batch still follows the channels' order
  stream->add(true, "d");
  const auto restX = drain(*x);
  const std::uint64_t encodes = stream->frameEncodes();
  const auto restY = drain(*y);
  CHECK(stream->frameEncodes() == encodes);  // y was handed x's batch
  REQUIRE(restX.size() == 2);
  CHECK(restX[0].bytes() == "first: c");
  CHECK(restX[1].bytes() == "second: b d");
  REQUIRE(restY.size() == 2);
  CHECK(restY[0].shared == restX[0].shared);

  stream->add(false, "e");
  stream->end();
  const auto last = drain(*x);
  REQUIRE(last.size() == 2);
  CHECK(last[0].bytes() == "first: e");
  CHECK(last[1].bytes() == "done");
  CHECK(last[1].last);
  CHECK_FALSE(x->next());
}

TEST_CASE("study stream: snapshot, progress with the summary only when it changed, done last") {
  auto stream = std::make_shared<studies::StudyStream>();
  studies::StudyState s;
  s.id = "s1";
  s.status = RunStatus::Running;
  s.total = 10;
  stream->update(s);
  auto sub = stream->subscribe(std::make_shared<NoWake>());
  CHECK(sub->minInterval() == std::chrono::milliseconds(250));
  auto frames = drain(*sub);
  REQUIRE(frames.size() == 1);
  json j = json::parse(frames[0].bytes());
  CHECK(j["type"] == "snapshot");
  CHECK(j["study"]["id"] == "s1");
  CHECK(j["summary"].is_null());

  s.done = 3;
  stream->update(s);
  frames = drain(*sub);
  REQUIRE(frames.size() == 1);
  j = json::parse(frames[0].bytes());
  CHECK(j["type"] == "progress");
  CHECK(j["runs_done"] == 3);
  CHECK_FALSE(j.contains("summary"));

  stream->setSummary(json{{"runs", 3}});
  s.done = 4;
  stream->update(s);
  frames = drain(*sub);
  REQUIRE(frames.size() == 1);  // two changes, one frame
  j = json::parse(frames[0].bytes());
  CHECK(j["runs_done"] == 4);
  CHECK(j["summary"]["runs"] == 3);

  s.done = 10;
  s.status = RunStatus::Succeeded;
  stream->update(s);
  frames = drain(*sub);
  REQUIRE(frames.size() == 1);  // the done frame carries the last state
  CHECK(frames[0].last);
  j = json::parse(frames[0].bytes());
  CHECK(j["type"] == "done");
  CHECK(j["runs_done"] == 10);
  CHECK(j["status"] == "succeeded");

  // A late joiner of an ended study: the snapshot, then done.
  auto late = stream->subscribe(std::make_shared<NoWake>());
  frames = drain(*late);
  REQUIRE(frames.size() == 2);
  CHECK(json::parse(frames[0].bytes())["type"] == "snapshot");
  CHECK(json::parse(frames[1].bytes())["type"] == "done");
}
