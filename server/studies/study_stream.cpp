#include "server/studies/study_stream.hpp"

#include <cmath>

namespace rover::studies {

using nlohmann::json;

namespace {

json progressJson(const StudyState& s) {
  return json{{"type", "progress"}, {"status", enumName(s.status)},     {"message", s.message},
              {"runs_done", s.done}, {"runs_total", s.total},
              {"eta_s", s.etaSeconds < 0 ? json(nullptr) : json(std::round(s.etaSeconds))},
              {"runs_per_s", s.runsPerSecond}};
}

}  // namespace

// Every change is a cut at once (a study changes a few times a second); a subscriber reads at
// most every 250 ms, which coalesces the states in between.
StudyStream::StudyStream()
    : ChannelStream({std::chrono::milliseconds(0), std::chrono::milliseconds(0), std::chrono::milliseconds(250)}) {
  addChannel(progress_);
}

std::size_t StudyStream::Progress::frames(const streams::Position& from, const streams::Position& to,
                                          streams::Batch& out) {
  // After the end the done frame carries the state.
  if (from == to || isFinal(state.status)) return 0;
  std::size_t encoded = 0;
  if (encodedAt_ != to) plain_.reset(), withSummary_.reset(), encodedAt_ = to;
  const bool summaryChanged = streams::lengthAt(from, 1) != streams::lengthAt(to, 1);
  std::shared_ptr<const std::string>& frame = summaryChanged ? withSummary_ : plain_;
  if (!frame) {
    json j = progressJson(state);
    if (summaryChanged) j["summary"] = summary;
    frame = std::make_shared<const std::string>(j.dump());
    encoded = 1;
  }
  out.emplace_back(false, frame, false);
  return encoded;
}

std::function<streams::Batch()> StudyStream::captureSnapshotLocked() {
  return [j = json{{"type", "snapshot"}, {"study", toJson(progress_.state)}, {"summary", progress_.summary}}] {
    return streams::Batch{http::WsFrame{false, std::make_shared<const std::string>(j.dump()), false}};
  };
}

std::shared_ptr<const std::string> StudyStream::doneFrameLocked() {
  const streams::Position at = progress_.position();
  if (!done_ || doneAt_ != at) {
    const StudyState& s = progress_.state;
    done_ = std::make_shared<const std::string>(json{{"type", "done"}, {"status", enumName(s.status)}, {"message", s.message},
                                                     {"runs_done", s.done}, {"runs_total", s.total},
                                                     {"summary", progress_.summary}}
                                                    .dump());
    doneAt_ = at;
    countEncodes(1);
  }
  return done_;
}

void StudyStream::update(const StudyState& state) {
  {
    std::lock_guard lock(mutex_);
    progress_.state = state;
    ++progress_.version;
    changedLocked();
  }
  wakeAll(true);
}

void StudyStream::setSummary(json summary) {
  {
    std::lock_guard lock(mutex_);
    progress_.summary = std::move(summary);
    ++progress_.summaryVersion;
    changedLocked();
  }
  wakeAll(true);
}

}  // namespace rover::studies
