// WS /api/events (issue 26) over loopback: 4 writers and 50 subscribers, every subscriber gets
// every event once, in order, without a gap; a reconnect with ?since= replays the rest; an old
// since is told to resync; hostile since values are refused naming the field; presence comes and
// goes with its connection; the numbering continues after a restart. Counts are bounded; waits
// are on events (tests/wait_until.hpp), never on durations.
#include <doctest/doctest.h>

#include <atomic>
#include <thread>

#include "api_server.hpp"
#include "event_client.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::EventClient;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

// a + b, appended (GCC 12 warns on `"x" + std::to_string(n)`, -Wrestrict).
std::string cat(std::string a, const std::string& b) {
  a += b;
  return a;
}

test::HttpResult upgrade(unsigned short port, const std::string& target) {
  return request(port, "GET", target, "", "",
                 {{"Upgrade", "websocket"}, {"Connection", "Upgrade"}, {"Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="},
                  {"Sec-WebSocket-Version", "13"}});
}

test::ApiServerOptions options() {
  test::ApiServerOptions o;
  o.workers = 1;
  o.http.threads = 2;
  return o;
}

std::string newPdm(ApiServer& s, const std::string& map, const std::string& name) {
  auto p = s.postJson("/api/maps/" + map + "/pdms", {{"name", name}, {"components", json::array({{{"x", 50}, {"y", 50}, {"sigma_x", 10}}})}});
  REQUIRE(p.status == 201);
  return "/api/maps/" + map + "/pdms/" + p.json()["id"].get<std::string>();
}

}  // namespace

TEST_CASE("events: 4 writers, 50 subscribers: every event to every subscriber in order, then replay from since") {
  constexpr int kWriters = 4, kWritesEach = 50, kSubscribers = 50, kEvents = kWriters * kWritesEach;
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  std::vector<std::string> pdms;
  for (int w = 0; w < kWriters; ++w) pdms.push_back(newPdm(s, map, cat("writer ", std::to_string(w))));
  const std::uint64_t before = s.ctx.events->lastSeq();

  std::atomic<int> ready{0}, done{0}, gaps{0}, disorder{0}, lost{0};
  std::vector<std::thread> subscribers;
  for (int k = 0; k < kSubscribers; ++k)
    subscribers.emplace_back([&] {
      EventClient c(s.port(), "/api/events");
      const json r = c.nextOf("ready");
      if (r.is_null()) {
        ++lost;
        ++ready;
        ++done;
        return;
      }
      std::uint64_t last = r["seq"];
      ++ready;
      std::map<std::string, long long> versions;  // per PDM: versions only grow
      int seen = 0;
      while (seen < kEvents) {
        const json m = c.next();
        if (m.is_null()) {
          ++lost;
          break;
        }
        if (m["type"] != "events") continue;
        for (const json& e : m["events"]) {
          if (e["seq"].get<std::uint64_t>() != last + 1) ++gaps;
          last = e["seq"];
          long long& v = versions[e["id"]];
          if (e["version"].get<long long>() <= v) ++disorder;
          v = e["version"];
          ++seen;
        }
      }
      ++done;
    });
  test::waitUntil([&] { return ready.load() == kSubscribers; }, test::kHangDeadline, "50 subscribers ready");

  std::vector<std::thread> writers;
  std::atomic<int> refused{0};
  for (int w = 0; w < kWriters; ++w)
    writers.emplace_back([&, w] {
      for (int i = 0; i < kWritesEach; ++i) {
        const auto r = request(s.port(), "PUT", pdms[w], json{{"name", cat("n", std::to_string(i))}, {"version", i + 1}}.dump(),
                               "application/json");
        if (r.status != 200) ++refused;
      }
    });
  for (auto& t : writers) t.join();
  CHECK(refused.load() == 0);
  test::waitUntil([&] { return done.load() == kSubscribers; }, test::kHangDeadline, "every subscriber got every event");
  for (auto& t : subscribers) t.join();
  CHECK(lost.load() == 0);
  CHECK(gaps.load() == 0);
  CHECK(disorder.load() == 0);
  CHECK(s.ctx.events->lastSeq() == before + kEvents);

  // A reconnect from the middle: exactly the rest, in order, then ready at the newest.
  EventClient again(s.port(), cat("/api/events?since=", std::to_string(before + 100)));
  std::uint64_t last = before + 100;
  int replayed = 0;
  for (json m = again.next(); !m.is_null(); m = again.next()) {
    if (m["type"] == "ready") {
      CHECK(m["seq"] == before + kEvents);
      break;
    }
    REQUIRE(m["type"] == "events");
    for (const json& e : m["events"]) {
      CHECK(e["seq"] == last + 1);
      last = e["seq"];
      ++replayed;
    }
  }
  CHECK(replayed == kEvents - 100);

  // A filtered stream gets this map's events and nothing of another map's.
  EventClient filtered(s.port(), "/api/events?map=" + map + cat("&since=", std::to_string(before)));
  const json first = filtered.next();
  REQUIRE(first["type"] == "events");
  CHECK(first["events"][0]["map"] == map);
}

TEST_CASE("events: hostile since values are refused naming since; an old one is told to resync") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const auto last = s.ctx.events->lastSeq();
  checkError(upgrade(s.port(), "/api/events?since=-1"), 400, "since");
  checkError(upgrade(s.port(), "/api/events?since=1e300"), 400, "since");
  checkError(upgrade(s.port(), "/api/events?since=abc"), 400, "since");
  // Decimal digits only (an attack found 0x10 read as 16 and 1e1 as 10).
  for (const char* odd : {"0x10", "1e1", "%205", "5.0"})
    checkError(upgrade(s.port(), cat("/api/events?since=", odd)), 400, "since");
  checkError(upgrade(s.port(), cat("/api/events?since=", std::to_string(last + 5))), 400, "since");
  checkError(upgrade(s.port(), "/api/events?map=nope"), 404, "map");
  // More events than the ring keeps: a subscriber from before them must reload.
  for (std::size_t i = 0; i < streams::EventHub::kRingEvents + 10; ++i)
    s.ctx.events->publish({"changed", "study", cat("s", std::to_string(i)), "", 0, "", nullptr});
  EventClient old(s.port(), cat("/api/events?since=", std::to_string(last)));
  const json m = old.next();
  CHECK(m["type"] == "resync_required");
  CHECK(m["oldest"] == last + 11);
  CHECK(old.next().is_null());  // then closed
  // From inside the ring it replays.
  EventClient recent(s.port(), cat("/api/events?since=", std::to_string(last + 4100)));
  CHECK(recent.next()["events"].size() == 6);
}

TEST_CASE("events: presence never pushes a change event out of the ring") {
  // An attack: 200 connections saying hello every 0.2 s emptied the ring of real events in 20 s.
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const auto before = s.ctx.events->lastSeq();
  s.ctx.events->publish({"changed", "study", "s-real", "", 1, "", nullptr});
  for (std::size_t i = 0; i < streams::EventHub::kRingEvents + 100; ++i)
    s.ctx.events->publish({"presence", "presence", cat("c", std::to_string(i)), "", 0, "", nullptr});
  CHECK(s.ctx.events->oldestSeq() == before + 1);
  EventClient c(s.port(), cat("/api/events?since=", std::to_string(before)));
  const json m = c.next();
  REQUIRE(m["type"] == "events");
  CHECK(m["events"][0]["id"] == "s-real");
  // Then only the newest presence events (presence is state: "ready" carries it whole).
  CHECK(m["events"].size() == streams::EventHub::kPresenceKept + 1);
  CHECK(m["events"].back()["seq"] == s.ctx.events->lastSeq());
}

TEST_CASE("events: presence says who has which map open and goes with the connection") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  EventClient watcher(s.port(), "/api/events?map=" + map);
  REQUIRE(watcher.nextOf("ready")["presence"].empty());
  {
    EventClient ada(s.port(), "/api/events?map=" + map);
    REQUIRE(!ada.nextOf("ready").is_null());
    ada.send({{"type", "hello"}, {"name", "Ada"}, {"map", map}, {"editing", "zones"}});
    ada.send({{"type", "hello"}, {"name", "Ada"}, {"map", map}, {"editing", "zones"}});  // the same: no event
    ada.send(json("not an object"));                                                    // ignored
    const json e = watcher.nextOf("events")["events"][0];
    CHECK(e["kind"] == "presence");
    CHECK(e["by"] == "Ada");
    CHECK(e["extra"]["editing"] == "zones");
    EventClient late(s.port(), "/api/events");
    const json list = late.nextOf("ready")["presence"];
    REQUIRE(list.size() == 1);
    CHECK(list[0]["name"] == "Ada");
    // A real change comes next, not a second presence event.
    REQUIRE(s.postJson("/api/maps/" + map + "/zones", json{{"type", "Feature"},
                                                          {"properties", json::object()},
                                                          {"geometry", {{"type", "Polygon"},
                                                                        {"coordinates", {{{60, 40}, {90, 40}, {90, 110}, {60, 40}}}}}}})
                .status == 201);
    const json change = watcher.nextOf("events")["events"][0];
    CHECK(change["object"] == "zone");
    CHECK(change["kind"] == "created");
  }
  const json left = watcher.nextOf("events")["events"][0];
  CHECK(left["kind"] == "left");
  CHECK(left["extra"]["name"] == "Ada");
}

TEST_CASE("events: the numbering continues after a restart") {
  TempDir tmp;
  std::uint64_t last = 0;
  {
    ApiServer s(tmp.str("data"), options());
    newPdm(s, s.defaultMap(), "one");
    newPdm(s, s.defaultMap(), "two");
    last = s.ctx.events->lastSeq();
    CHECK(last >= 2);
  }
  ApiServer again(tmp.str("data"), options());
  CHECK(again.ctx.events->lastSeq() == last);
  EventClient c(again.port(), cat("/api/events?since=", std::to_string(last)));
  REQUIRE(c.nextOf("ready")["seq"] == last);
  newPdm(again, again.defaultMap(), "three");
  CHECK(c.nextOf("events")["events"][0]["seq"] == last + 1);
}

TEST_CASE("events: a map rename is a changed map event with its new version, by its operator") {
  TempDir tmp;
  ApiServer s(tmp.str("data"), options());
  const std::string map = s.defaultMap();
  EventClient watcher(s.port(), "/api/events?map=" + map);
  REQUIRE(!watcher.nextOf("ready").is_null());
  auto r = request(s.port(), "PATCH", "/api/maps/" + map, json{{"name", "Gale east"}}.dump(), "application/json",
                   {{"If-Match", "\"v1\""}});
  REQUIRE(r.status == 200);
  const json e = watcher.nextOf("events")["events"][0];
  CHECK(e["kind"] == "changed");
  CHECK(e["object"] == "map");
  CHECK(e["id"] == map);
  CHECK(e["map"] == map);
  CHECK(e["version"] == 2);
  // A refused rename sends nothing: the next event is the next change.
  REQUIRE(request(s.port(), "PATCH", "/api/maps/" + map, json{{"name", "x"}}.dump(), "application/json",
                  {{"If-Match", "\"v1\""}}).status == 412);
  newPdm(s, map, "after");
  CHECK(watcher.nextOf("events")["events"][0]["object"] == "pdm");
}
