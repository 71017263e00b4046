#pragma once
// The live state of one study and its WebSocket subscribers: a ChannelStream
// (server/streams/channel_stream.hpp) like the missions', of one channel, "progress", whose
// position is the state's version and the summary's (the wire format folds a new summary into
// the progress frame). A slow client costs a cursor and intermediate states coalesce. Frames
// (text):
//   {"type":"snapshot", study{...state}, summary}           first
//   {"type":"progress", done, total, eta_s, runs_per_s, status, summary?}  summary: when it changed
//   {"type":"done", status, message, done, total, summary}  last, then a normal close
// Each frame is encoded once per state and shared by every subscriber (issue 22): a crowd of
// readers costs the study thread nothing but the wake-ups.
#include <cstdint>
#include <memory>

#include <nlohmann/json.hpp>

#include "server/streams/channel_stream.hpp"
#include "server/studies/study_state.hpp"

namespace rover::studies {

class StudyStream : public streams::ChannelStream {
 public:
  StudyStream();
  void update(const StudyState& state);     // progress / status
  void setSummary(nlohmann::json summary);  // the partial (or final) summary

 private:
  class Progress : public streams::Channel {
   public:
    Progress() : Channel("progress") {}
    StudyState state;
    nlohmann::json summary = nullptr;
    std::uint64_t version = 0, summaryVersion = 0;
    streams::Position position() const override { return {version, summaryVersion}; }
    std::size_t frames(const streams::Position& from, const streams::Position& to, streams::Batch& out) override;

   private:
    // The two frames of a position `to` (with the summary, when it changed since `from`).
    streams::Position encodedAt_;
    std::shared_ptr<const std::string> plain_, withSummary_;
  };
  std::function<streams::Batch()> captureSnapshotLocked() override;
  bool endedLocked() const override { return isFinal(progress_.state.status); }
  std::shared_ptr<const std::string> doneFrameLocked() override;

  Progress progress_;
  streams::Position doneAt_;
  std::shared_ptr<const std::string> done_;
};

}  // namespace rover::studies
