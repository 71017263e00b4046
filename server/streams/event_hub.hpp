#pragma once
// The one live event stream of the API (issue 26): every create/change/delete of maps, PDMs,
// zones, missions and studies, and the operators' presence, as events {seq, kind, object, id, map,
// version, by, at} under one global, gap-free sequence number.
//
// Bounds: the newest kRingEvents events are kept in memory (each at most a few hundred bytes, so
// about 1.5 MB); the last sequence number is stored on every publish (the database's counters
// table), so a restart continues the numbering. A subscriber joins with ?since=N: the events after
// N are replayed from the ring, or, when N is older than the ring, it is sent one
// {"type":"resync_required"} message and closed (reload the lists, then join from the seq of its
// answer). Fan-out is the mission streams' machinery (channel_stream.hpp): events are published
// in cuts, each batch of events from one cut to the newest is encoded once and shared by every
// subscriber standing at that cut, and a slow subscriber simply stands at an older cut (it gets
// everything it missed in one message, or resync_required once it falls behind the ring). A
// subscriber may filter by map: it gets that map's events, the events of no map (studies) and
// every map's own created/deleted events (so map lists stay current); its seq then skips the
// other maps' numbers.
//
// Presence: a subscriber may send {"type":"hello","name":..,"map":..,"editing":..}; the hub
// publishes a "presence" event (object "presence", id the connection's) and a "left" one when the
// connection ends. The current presence list comes with the "ready" message a joiner is sent. At
// most kHelloPerSecond hellos per connection are taken (more are dropped), identical ones never.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "server/http/http_types.hpp"

namespace rover::streams {

struct Event {
  std::string kind;       // created | changed | deleted | presence | left
  std::string object;     // map | pdm | zone | zones | mission | study | presence
  std::string id;         // the object's id (a zone's: "MAP/zN" is not used: `map` says the map)
  std::string map;        // the map it belongs to, "" when none (studies)
  long long version = 0;  // the object's version after the change, 0 when it has none (deleted)
  std::string by;         // the operator, "" when unknown
  nlohmann::json extra;   // presence: {name, editing}; null otherwise
};

class EventHub : public std::enable_shared_from_this<EventHub> {
 public:
  static constexpr std::size_t kRingEvents = 4096;
  // Presence events kept besides them (the oldest dropped first): presence is state, sent whole
  // with "ready", so hellos can never push a change event out of the ring (an attack did: 200
  // connections saying hello every 0.2 s emptied it of real events in 20 s).
  static constexpr std::size_t kPresenceKept = 256;
  static constexpr int kHelloPerSecond = 5;

  // `lastSeq`: the last sequence number handed out by the previous run; `persist` stores each
  // new one (a failure to store it, e.g. a full disk, is not fatal: the event is still sent).
  EventHub(std::uint64_t lastSeq, std::function<void(std::uint64_t)> persist);
  ~EventHub();
  EventHub(const EventHub&) = delete;
  EventHub& operator=(const EventHub&) = delete;

  // Numbers, stores and sends `e`; returns its seq. Thread-safe.
  std::uint64_t publish(Event e);
  // A subscriber from `since` (nullopt: from now; must be <= lastSeq()), filtered to `map`
  // ("" = all). `who`: the connection's operator, the presence name until a hello says another.
  std::shared_ptr<http::WsSource> subscribe(std::shared_ptr<http::WsConnection> connection,
                                            std::optional<std::uint64_t> since, const std::string& map,
                                            const std::string& who, bool whoFixed = false);
  std::uint64_t lastSeq() const;
  std::uint64_t oldestSeq() const;  // the oldest event in the ring, lastSeq() + 1 when none
  std::size_t subscriberCount() const;

 private:
  class Stream;
  class Channel;
  class Source;
  friend class Source;
  struct Stored {
    std::uint64_t seq;
    std::string map;
    bool everyMap;  // sent to every map's subscribers (a map's own events, events of no map)
    bool presence;  // a presence or left event (kPresenceKept of them, apart from kRingEvents)
    std::shared_ptr<const std::string> json;
  };
  struct Presence {
    std::string name, map, editing;
  };
  // The events in (from, to] that `filter` lets through, as one message (none when no event);
  // a resync_required message (closing) when `from` is older than the ring. Takes mutex_.
  void framesFor(std::uint64_t from, std::uint64_t to, const std::string& filter, std::vector<http::WsFrame>& out) const;
  nlohmann::json presenceList(const std::string& filter) const;
  void setPresence(const std::string& id, std::optional<Presence> p, const std::string& by);
  std::shared_ptr<Stream> streamFor(const std::string& filter);

  mutable std::mutex mutex_;  // ring_, last_, presence_
  std::deque<Stored> ring_;  // ascending seq; presence events may leave gaps
  std::uint64_t last_;
  // Every change event after floor_ is in the ring (a `since` below it must resync): the last
  // evicted change event's seq, or the seq the hub started at.
  std::uint64_t floor_;
  std::size_t presenceInRing_ = 0;
  std::map<std::string, Presence> presence_;
  std::function<void(std::uint64_t)> persist_;
  std::mutex publishMutex_;  // one publish at a time: numbered, stored and ringed in order
  mutable std::mutex streamsMutex_;
  std::map<std::string, std::shared_ptr<Stream>> streams_;  // by map filter ("" = all)
  std::uint64_t nextConnection_ = 0;                        // under streamsMutex_
};

}  // namespace rover::streams
