#include "server/streams/event_hub.hpp"

#include <algorithm>

#include "server/http/request_origin.hpp"
#include "server/store/database.hpp"
#include "server/streams/channel_stream.hpp"

namespace rover::streams {

namespace {

constexpr const char* kChannel = "events";

std::uint64_t seqAt(const Cursor& c) {
  const Position& p = c[kChannel];
  return p.empty() ? 0 : p[0];
}

http::WsFrame textFrame(const nlohmann::json& j, bool last = false) { return http::WsFrame(false, j.dump(), last); }

// A short text field of a client message: a string of at most `max` bytes without control
// characters, else "".
std::string shortText(const nlohmann::json& j, const char* key, std::size_t max) {
  auto it = j.find(key);
  if (it == j.end() || !it->is_string()) return "";
  std::string s = it->get<std::string>();
  if (s.size() > max) return "";
  for (unsigned char c : s)
    if (c < 0x20 || c == 0x7f) return "";
  return s;
}

}  // namespace

// The ring as a channel: its position is the last seq; a batch is the events between two cuts.
class EventHub::Channel : public streams::Channel {
 public:
  Channel(const EventHub& hub, std::string filter) : streams::Channel(kChannel), hub_(hub), filter_(std::move(filter)) {}
  Position position() const override { return {hub_.lastSeq()}; }
  std::size_t frames(const Position& from, const Position& to, Batch& out) override {
    const std::size_t before = out.size();
    hub_.framesFor(from.empty() ? 0 : from[0], to.empty() ? 0 : to[0], filter_, out);
    return out.size() - before;
  }

 private:
  const EventHub& hub_;
  const std::string filter_;
};

// The subscribers of one filter: a ChannelStream of one channel, every subscriber joining by a
// replay (never the shared snapshot), and never ending.
class EventHub::Stream : public ChannelStream {
 public:
  // Cut at every publish (events are few and each counts); a subscriber's messages at least
  // 10 ms apart, so a burst reaches a browser as a few messages, not hundreds.
  Stream(const EventHub& hub, std::string filter)
      : ChannelStream(Pacing{std::chrono::milliseconds(0), std::chrono::milliseconds(0), std::chrono::milliseconds(10)}),
        channel_(hub, std::move(filter)) {
    addChannel(channel_);
    // The first joiner takes a cut: a new stream stands where the hub is, not at seq 0.
    std::lock_guard lock(mutex_);
    changedLocked();
  }
  void published() {
    {
      std::lock_guard lock(mutex_);
      changedLocked();
    }
    wakeAll(true);
  }
  using ChannelStream::subscribe;

 protected:
  std::function<Batch()> captureSnapshotLocked() override {
    return [] { return Batch{}; };
  }
  bool endedLocked() const override { return false; }
  std::shared_ptr<const std::string> doneFrameLocked() override { return std::make_shared<const std::string>(); }

 private:
  Channel channel_;
};

// One subscriber: the stream's subscription, plus its presence (hello messages in, "left" when
// it goes).
class EventHub::Source : public http::WsSource {
 public:
  Source(std::shared_ptr<EventHub> hub, std::shared_ptr<Stream> stream, std::shared_ptr<http::WsSource> inner,
         std::string id, std::string who, bool whoFixed)
      : hub_(std::move(hub)), stream_(std::move(stream)), inner_(std::move(inner)), id_(std::move(id)), who_(std::move(who)),
        whoFixed_(whoFixed) {}
  ~Source() override {
    if (announced_) hub_->setPresence(id_, std::nullopt, who_);
  }
  std::optional<http::WsFrame> next() override { return inner_->next(); }
  std::chrono::milliseconds minInterval() const override { return inner_->minInterval(); }
  void onMessage(const std::string& text) override {
    nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (!j.is_object() || j.value("type", "") != "hello") return;
    Presence p;
    // A named token says who it is, as on every REST route; otherwise the hello may.
    if (auto name = http::validOperatorName(shortText(j, "name", 4 * http::kMaxOperatorChars));
        !whoFixed_ && name && !name->empty())
      p.name = *name;
    else
      p.name = who_;
    p.map = shortText(j, "map", 128);
    p.editing = shortText(j, "editing", 200);
    if (announced_ && p.name == last_.name && p.map == last_.map && p.editing == last_.editing) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - windowStart_ >= std::chrono::seconds(1)) {
      windowStart_ = now;
      inWindow_ = 0;
    }
    if (++inWindow_ > kHelloPerSecond) return;
    last_ = p;
    announced_ = true;
    hub_->setPresence(id_, p, p.name);
  }

 private:
  std::shared_ptr<EventHub> hub_;
  std::shared_ptr<Stream> stream_;
  std::shared_ptr<http::WsSource> inner_;
  const std::string id_, who_;
  const bool whoFixed_;
  bool announced_ = false;
  Presence last_;
  std::chrono::steady_clock::time_point windowStart_{};
  int inWindow_ = 0;
};

EventHub::EventHub(std::uint64_t lastSeq, std::function<void(std::uint64_t)> persist)
    : last_(lastSeq), floor_(lastSeq), persist_(std::move(persist)) {}

EventHub::~EventHub() = default;

std::uint64_t EventHub::lastSeq() const {
  std::lock_guard lock(mutex_);
  return last_;
}

std::uint64_t EventHub::oldestSeq() const {
  std::lock_guard lock(mutex_);
  return floor_ + 1;
}

std::uint64_t EventHub::publish(Event e) {
  std::lock_guard order(publishMutex_);
  std::uint64_t seq;
  {
    std::lock_guard lock(mutex_);
    seq = last_ + 1;
  }
  try {
    if (persist_) persist_(seq);
  } catch (const std::exception&) {
    // A full disk: the event still goes out; a restart may then number from an older seq, which
    // a client resuming sees as resync_required (its since is newer than the ring).
  }
  nlohmann::json j{{"seq", seq},          {"kind", e.kind}, {"object", e.object},   {"id", e.id},
                   {"map", e.map},        {"version", e.version}, {"by", e.by}, {"at", store::nowIso()}};
  if (!e.extra.is_null()) j["extra"] = e.extra;
  const bool everyMap = e.map.empty() || e.object == "map";
  {
    std::lock_guard lock(mutex_);
    const bool presence = e.object == "presence";
    ring_.push_back(Stored{seq, e.map, everyMap, presence, std::make_shared<const std::string>(j.dump())});
    if (presence && ++presenceInRing_ > kPresenceKept) {
      // The oldest presence event goes; change events stay where they are.
      auto oldest = std::find_if(ring_.begin(), ring_.end(), [](const Stored& s) { return s.presence; });
      ring_.erase(oldest);
      --presenceInRing_;
    }
    while (ring_.size() - presenceInRing_ > kRingEvents) {
      if (ring_.front().presence) --presenceInRing_;
      else floor_ = ring_.front().seq;
      ring_.pop_front();
    }
    last_ = seq;
  }
  std::vector<std::shared_ptr<Stream>> wake;
  {
    std::lock_guard lock(streamsMutex_);
    for (const auto& [filter, s] : streams_)
      if (filter.empty() || everyMap || filter == e.map) wake.push_back(s);
  }
  for (auto& s : wake) s->published();
  return seq;
}

void EventHub::framesFor(std::uint64_t from, std::uint64_t to, const std::string& filter,
                         std::vector<http::WsFrame>& out) const {
  if (to <= from) return;
  std::lock_guard lock(mutex_);
  const std::uint64_t oldest = floor_ + 1;
  if (from < floor_) {
    out.push_back(textFrame({{"type", "resync_required"},
                             {"since", from},
                             {"oldest", oldest},
                             {"message", "the events after " + std::to_string(from) +
                                             " are no longer kept (the server keeps the last " +
                                             std::to_string(kRingEvents) +
                                             "): reload the lists and join again with since= the seq you then read"}},
                            true));
    return;
  }
  std::string body = "{\"type\":\"events\",\"events\":[";
  bool any = false;
  // The ring is in ascending seq (presence events may have left gaps): the first after `from`.
  auto first = std::lower_bound(ring_.begin(), ring_.end(), from + 1,
                                [](const Stored& s, std::uint64_t seq) { return s.seq < seq; });
  for (auto it = first; it != ring_.end() && it->seq <= to; ++it) {
    const Stored& s = *it;
    if (!filter.empty() && !s.everyMap && s.map != filter) continue;
    if (any) body.push_back(',');
    body += *s.json;
    any = true;
  }
  if (!any) return;
  body += "]}";
  out.emplace_back(false, std::move(body));
}

nlohmann::json EventHub::presenceList(const std::string& filter) const {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [id, p] : presence_)
    if (filter.empty() || p.map == filter)
      list.push_back({{"id", id}, {"name", p.name}, {"map", p.map}, {"editing", p.editing}});
  return list;
}

void EventHub::setPresence(const std::string& id, std::optional<Presence> p, const std::string& by) {
  std::vector<Event> events;
  auto left = [&](const Presence& was) {
    Event e;
    e.kind = "left";
    e.object = "presence";
    e.id = id;
    e.map = was.map;
    e.by = by;
    e.extra = {{"name", was.name}};
    events.push_back(std::move(e));
  };
  {
    std::lock_guard lock(mutex_);
    auto it = presence_.find(id);
    if (p) {
      // Moving to another map: that map's subscribers see it leave first.
      if (it != presence_.end() && it->second.map != p->map) left(it->second);
      Event e;
      e.kind = "presence";
      e.object = "presence";
      e.id = id;
      e.map = p->map;
      e.by = by;
      e.extra = {{"name", p->name}, {"editing", p->editing}};
      events.push_back(std::move(e));
      presence_[id] = *p;
    } else {
      if (it == presence_.end()) return;
      left(it->second);
      presence_.erase(it);
    }
  }
  for (auto& e : events) publish(std::move(e));
}

std::shared_ptr<EventHub::Stream> EventHub::streamFor(const std::string& filter) {
  std::lock_guard lock(streamsMutex_);
  // Streams without subscribers go (their number stays within the subscriber limits).
  for (auto it = streams_.begin(); it != streams_.end();)
    if (it->first != filter && it->second->subscriberCount() == 0) it = streams_.erase(it);
    else ++it;
  auto& s = streams_[filter];
  if (!s) s = std::make_shared<Stream>(*this, filter);
  return s;
}

std::shared_ptr<http::WsSource> EventHub::subscribe(std::shared_ptr<http::WsConnection> connection,
                                                    std::optional<std::uint64_t> since, const std::string& map,
                                                    const std::string& who, bool whoFixed) {
  auto stream = streamFor(map);
  std::string id;
  {
    std::lock_guard lock(streamsMutex_);
    id = "c" + std::to_string(++nextConnection_);
  }
  auto self = shared_from_this();
  auto inner = stream->subscribe(std::move(connection), [self, since, map, id](const Cursor& at) {
    Batch b;
    const std::uint64_t seq = seqAt(at);
    if (since && *since < seq) {
      self->framesFor(*since, seq, map, b);
      if (!b.empty() && b.back().last) return b;  // resync_required: nothing follows
    }
    std::lock_guard lock(self->mutex_);
    b.push_back(textFrame({{"type", "ready"},
                           {"seq", seq},
                           {"connection", id},
                           {"ring", kRingEvents},
                           {"presence", self->presenceList(map)}}));
    return b;
  });
  return std::make_shared<Source>(self, std::move(stream), std::move(inner), id, who, whoFixed);
}

std::size_t EventHub::subscriberCount() const {
  std::lock_guard lock(streamsMutex_);
  std::size_t n = 0;
  for (const auto& [f, s] : streams_) n += s->subscriberCount();
  return n;
}

}  // namespace rover::streams
