// WS /api/events (issue 26): the one live stream of every change, for every page and tool
// (server/streams/event_hub.hpp says what it sends and keeps).
#include "server/api/route_kit.hpp"

namespace rover::api {

void addEventRoutes(http::Router& router, ApiContext& ctx) {
  http::RouteOptions ws;
  ws.openapi = Operation().errors({400, 404, 503}).toJson();  // 503: subscriber limits (ws_admission.hpp)
  ws.openapi["x-messages"] = openapi::eventMessageSchema();      // what the server sends
  ws.summary =
      "WebSocket: every create/change/delete of maps, PDMs, zones, missions and studies, and operators' presence, as "
      "{type:\"events\", events:[{seq, kind, object, id, map, version, by, at}]} (x-websockets messages), seq global "
      "and gap-free. ?since=N replays the events after N (the last " +
      std::to_string(streams::EventHub::kRingEvents) +
      " are kept; older: one {type:\"resync_required\"} message, then close), then {type:\"ready\", seq, presence}; "
      "without since, only ready and what follows. ?map=ID: that map's events, maps' own and those of no map. "
      "Send {\"type\":\"hello\",\"name\":..,\"map\":..,\"editing\":..} to be shown to the others (presence).";
  router.addWebSocket("/api/events", [&ctx](const Request& req, std::shared_ptr<http::WsConnection> c) {
    std::optional<std::uint64_t> since;
    if (auto it = req.query.find("since"); it != req.query.end() && !it->second.empty()) {
      since = static_cast<std::uint64_t>(queryInteger(req, "since", 0, 0, (1LL << 53) - 1));
      const std::uint64_t last = ctx.events->lastSeq();
      if (*since > last)
        throw ApiError(400, "invalid_parameter",
                       "since is ahead of the newest event (" + std::to_string(last) +
                           "): send the seq of an event you received",
                       "since");
    }
    const std::string map = queryString(req, "map");
    if (!map.empty()) mapOr404(ctx, map, "map");
    return ctx.events->subscribe(std::move(c), since, map, req.operatorName, req.operatorFromToken);
  }, ws);
}

}  // namespace rover::api
