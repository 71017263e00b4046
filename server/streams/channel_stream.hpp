#pragma once
// A live stream as a set of named channels and one generic cursor (issue 23 item 4), after the
// shared state of Beast's chat-multi example: one object holds what is published and the set of
// sessions, each session keeps its own queue (here: the batch it is sending and the cursor it
// stands at). Missions (MissionStream) and studies (StudyStream) are both built on it.
//
// A channel is an append-only log (trail points, grid cells, overlay points) or a value
// overwritten in place (progress, status) with a position a reader has reached; a reader behind
// the channel's replay bound (the grid's compacted change log) is sent the channel's whole state.
// What subscribers are sent is published in cuts: a cut is every channel's position at one
// moment; a subscriber always stands at a cut, and the frames from one cut to the newest (a
// batch, each channel's frames in the order the channels were added) are encoded once and shared
// by every subscriber standing at that cut. A joiner gets the owner's snapshot, itself standing
// at a cut, reused up to `snapshotReuse` old (then caught up by a batch).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/http_types.hpp"

namespace rover::streams {

using Batch = std::vector<http::WsFrame>;
// How far a reader has read one channel: a version, or a length per rover.
using Position = std::vector<std::uint64_t>;

// Where a subscriber stands: a cut and every channel's position there, by channel name.
struct Cursor {
  std::uint64_t cut = 0;
  std::map<std::string, Position, std::less<>> at;
  const Position& operator[](std::string_view channel) const;  // empty for an unknown channel
};

// One channel of a stream. Its data is guarded by the stream's mutex: every call below is made
// with it held.
class Channel {
 public:
  explicit Channel(std::string name) : name_(std::move(name)) {}
  virtual ~Channel() = default;
  const std::string& name() const { return name_; }
  virtual Position position() const = 0;
  // A cut is taken from `from` to `to`: a value overwritten in place encodes its frame now, as
  // of this cut. Returns the frames encoded.
  virtual std::size_t cut(const Position& /*from*/, const Position& /*to*/) { return 0; }
  // Appends the frames that take a reader from `from` to `to`; returns how many it encoded (a
  // shared frame appended again is not counted).
  virtual std::size_t frames(const Position& from, const Position& to, Batch& out) = 0;

 private:
  std::string name_;
};

// A length of a per-rover position, 0 past its end.
inline std::uint64_t lengthAt(const Position& p, std::size_t k) { return k < p.size() ? p[k] : 0; }

class ChannelStream : public std::enable_shared_from_this<ChannelStream> {
 public:
  struct Pacing {
    std::chrono::milliseconds cutEvery;       // at most one cut per this on ordinary changes
    std::chrono::milliseconds snapshotReuse;  // a joiner may get a snapshot this old
    std::chrono::milliseconds minInterval;    // between a subscriber's frames (WsSource)
  };
  explicit ChannelStream(Pacing pacing) : pacing_(pacing) {}
  virtual ~ChannelStream() = default;
  ChannelStream(const ChannelStream&) = delete;
  ChannelStream& operator=(const ChannelStream&) = delete;

  std::shared_ptr<http::WsSource> subscribe(std::shared_ptr<http::WsConnection> connection);
  // A subscriber that starts from its own point instead of the shared snapshot (the event
  // stream's ?since=): `join` is called under the lock at a fresh cut, with that cut, and returns
  // the frames that bring this subscriber to it (a replay); it then follows as every subscriber.
  using Join = std::function<Batch(const Cursor&)>;
  std::shared_ptr<http::WsSource> subscribe(std::shared_ptr<http::WsConnection> connection, Join join);
  std::size_t subscriberCount() const;
  // How many snapshots were built so far: one per state that clients joined at.
  std::uint64_t snapshotBuilds() const { return snapshotBuilds_.load(); }
  // How many frames after the snapshot were encoded so far (shared by the subscribers at a cut).
  std::uint64_t frameEncodes() const { return frameEncodes_.load(); }

 protected:
  // What a joining client gets first, shared by all that join at the same state, with the cut
  // it stands for.
  struct Snapshot {
    Cursor at;
    std::chrono::steady_clock::time_point builtAt;
    Batch frames;
  };
  // Called under the lock at a fresh cut: copies what the snapshot shows and returns the work
  // that formats it, run after the lock is released (a big snapshot must not stall the writer).
  virtual std::function<Batch()> captureSnapshotLocked() = 0;
  virtual bool endedLocked() const = 0;
  // The last frame (sent with a normal close) once ended; encoded once (owner's cache).
  virtual std::shared_ptr<const std::string> doneFrameLocked() = 0;

  void addChannel(Channel& channel) { channels_.push_back(&channel); }  // constructor only
  void changedLocked() { ++stateVersion_; }  // a change a snapshot shows
  // Takes a cut when one is due (or at once when `force`: lifecycle changes) and wakes the
  // subscribers; a cut waits for at least one subscriber.
  void wakeAll(bool force);
  std::size_t subscriberSlotsLocked() const { return subscribers_.size(); }
  void countEncodes(std::size_t n) { frameEncodes_ += n; }

  mutable std::mutex mutex_;

 private:
  class Subscription;
  std::shared_ptr<const Snapshot> snapshot();
  std::shared_ptr<const Snapshot> joinAt(const Join& join);
  bool dirtyLocked() const { return stateVersion_ != headState_; }
  void cutLocked();
  std::shared_ptr<const Batch> batchLocked(const Cursor& from);

  const Pacing pacing_;
  std::vector<Channel*> channels_;
  std::vector<std::weak_ptr<http::WsConnection>> subscribers_;
  std::uint64_t stateVersion_ = 0, headState_ = 0;  // stateVersion_ at the newest cut
  Cursor head_;                                      // the newest cut
  std::chrono::steady_clock::time_point headAt_{};
  std::map<std::uint64_t, std::shared_ptr<const Batch>> batches_;  // by the cut they start from
  std::shared_ptr<const Snapshot> snapshot_;
  std::mutex snapshotBuildMutex_;  // one builder at a time; the others then share its snapshot
  std::atomic<std::uint64_t> snapshotBuilds_{0}, frameEncodes_{0};
};

}  // namespace rover::streams
