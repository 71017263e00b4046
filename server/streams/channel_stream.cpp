#include "server/streams/channel_stream.hpp"

namespace rover::streams {

const Position& Cursor::operator[](std::string_view channel) const {
  static const Position none;
  const auto it = at.find(channel);
  return it == at.end() ? none : it->second;
}

// One WebSocket client's place in the stream: the snapshot it was sent, the cut it stands at
// and the shared batch it is sending — its queue, in chat-multi's terms.
class ChannelStream::Subscription : public http::WsSource {
 public:
  Subscription(std::shared_ptr<ChannelStream> s, Join join) : stream_(std::move(s)), join_(std::move(join)) {}

  std::optional<http::WsFrame> next() override {
    ChannelStream& s = *stream_;
    if (!snapshot_) {
      // Built (or reused) outside the stream's lock; the cursor is that of its cut.
      snapshot_ = join_ ? s.joinAt(join_) : s.snapshot();
      at_ = snapshot_->at;
    }
    if (sentOfSnapshot_ < snapshot_->frames.size()) return snapshot_->frames[sentOfSnapshot_++];
    if (batch_ && sent_ < batch_->size()) return (*batch_)[sent_++];
    batch_.reset();

    std::lock_guard lock(s.mutex_);
    const bool ended = s.endedLocked();
    if (ended && s.dirtyLocked()) s.cutLocked();  // the end is published whole
    if (at_.cut != s.head_.cut) {
      std::shared_ptr<const Batch>& b = s.batches_[at_.cut];
      if (!b) b = s.batchLocked(at_);
      at_ = s.head_;
      batch_ = b;
      sent_ = 0;
      if (!batch_->empty()) return (*batch_)[sent_++];
    }
    if (ended && !doneSent_) {
      doneSent_ = true;
      return http::WsFrame{false, s.doneFrameLocked(), true};
    }
    return std::nullopt;
  }
  std::chrono::milliseconds minInterval() const override { return stream_->pacing_.minInterval; }

 private:
  std::shared_ptr<ChannelStream> stream_;
  Join join_;
  std::shared_ptr<const Snapshot> snapshot_;
  std::size_t sentOfSnapshot_ = 0;
  bool doneSent_ = false;
  Cursor at_;
  std::shared_ptr<const Batch> batch_;  // shared with the others at the same cut
  std::size_t sent_ = 0;                // frames of batch_ sent
};

std::shared_ptr<const ChannelStream::Snapshot> ChannelStream::snapshot() {
  std::lock_guard build(snapshotBuildMutex_);
  auto snap = std::make_shared<Snapshot>();
  std::function<Batch()> format;
  {
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    // The newest state, or one young enough: the joiner catches up from its cut by one batch.
    if (snapshot_ && ((snapshot_->at.cut == head_.cut && !dirtyLocked()) ||
                      (!endedLocked() && now - snapshot_->builtAt < pacing_.snapshotReuse)))
      return snapshot_;
    if (dirtyLocked()) cutLocked();  // the snapshot stands at a cut, as every subscriber does
    snap->at = head_;
    snap->builtAt = now;
    format = captureSnapshotLocked();
  }
  snap->frames = format();
  ++snapshotBuilds_;
  std::lock_guard lock(mutex_);
  snapshot_ = snap;
  return snap;
}

std::shared_ptr<const ChannelStream::Snapshot> ChannelStream::joinAt(const Join& join) {
  auto snap = std::make_shared<Snapshot>();
  std::lock_guard lock(mutex_);
  if (dirtyLocked()) cutLocked();
  snap->at = head_;
  snap->builtAt = std::chrono::steady_clock::now();
  snap->frames = join(head_);
  return snap;
}

void ChannelStream::cutLocked() {
  Cursor c;
  c.cut = head_.cut + 1;
  std::size_t encoded = 0;
  for (Channel* ch : channels_) {
    Position p = ch->position();
    encoded += ch->cut(head_[ch->name()], p);
    c.at.emplace(ch->name(), std::move(p));
  }
  frameEncodes_ += encoded;
  head_ = std::move(c);
  headState_ = stateVersion_;
  headAt_ = std::chrono::steady_clock::now();
  batches_.clear();  // the subscribers holding one keep it alive until sent
}

std::shared_ptr<const Batch> ChannelStream::batchLocked(const Cursor& from) {
  auto batch = std::make_shared<Batch>();
  std::size_t encoded = 0;
  for (Channel* ch : channels_) encoded += ch->frames(from[ch->name()], head_[ch->name()], *batch);
  frameEncodes_ += encoded;
  return batch;
}

std::shared_ptr<http::WsSource> ChannelStream::subscribe(std::shared_ptr<http::WsConnection> connection) {
  return subscribe(std::move(connection), nullptr);
}

std::shared_ptr<http::WsSource> ChannelStream::subscribe(std::shared_ptr<http::WsConnection> connection, Join join) {
  {
    std::lock_guard lock(mutex_);
    std::erase_if(subscribers_, [](const auto& w) { return w.expired(); });
    subscribers_.push_back(connection);
  }
  return std::make_shared<Subscription>(shared_from_this(), std::move(join));
}

std::size_t ChannelStream::subscriberCount() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& w : subscribers_) n += !w.expired();
  return n;
}

void ChannelStream::wakeAll(bool force) {
  std::vector<std::shared_ptr<http::WsConnection>> live;
  {
    std::lock_guard lock(mutex_);
    // A writer may change the stream thousands of times a second: the changes are published as
    // a cut at most every cutEvery, and only a cut wakes the subscribers (who then find a batch
    // to send). Lifecycle changes cut and wake at once.
    if (subscribers_.empty() || !dirtyLocked()) return;
    if (!force && std::chrono::steady_clock::now() - headAt_ < pacing_.cutEvery) return;
    cutLocked();
    for (const auto& w : subscribers_)
      if (auto c = w.lock()) live.push_back(std::move(c));
  }
  for (auto& c : live) c->wake();
}

}  // namespace rover::streams
