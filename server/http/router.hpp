#pragma once
// Route table: method + pattern ("/api/maps/{id}/layers/{layer}") -> handler. Patterns match whole
// path segments; a capture matches one non-empty segment. The table also feeds the OpenAPI
// document.
#include <string>
#include <vector>

#include "server/http/http_types.hpp"

namespace rover::http {

struct RouteOptions {
  bool streamBody = false;  // the body is streamed to a temp file (uploads), not kept in memory
  bool requireAuth = true;  // with --token, needs "Authorization: Bearer <token>"
  // Slow handler (GDAL, rendering, PDM discretisation, whole-DEM validation): runs on the
  // server's work pool, not on an io thread, so cheap requests keep being answered meanwhile.
  bool blocking = false;
  // With `blocking`: tried first on the io thread, so what is already made (a cached tile file)
  // is answered without a trip through the pool, whose queue renders wait in (issue 24: warm tiles
  // at 1/15 of nginx's rate). It may only look up memory and open a file the page cache holds;
  // nullopt hands the request to the pool, and what it throws is answered like a handler's.
  QuickHandler quick;
  std::string summary;      // one line for the OpenAPI document
  nlohmann::json openapi;   // extra OpenAPI operation fields (parameters, requestBody, responses)
};

struct Route {
  std::string method;  // "GET", "POST", "DELETE", or "WS" for a WebSocket upgrade (a GET)
  std::string pattern;
  Handler handler;
  WsHandler wsHandler;
  RouteOptions options;
};

class Router {
 public:
  void add(const std::string& method, const std::string& pattern, Handler h, RouteOptions o = {});
  void addWebSocket(const std::string& pattern, WsHandler h, RouteOptions o = {});

  struct Match {
    const Route* route = nullptr;  // null: no route for this method and path
    bool pathKnown = false;        // the path exists with another method (-> 405)
    std::map<std::string, std::string> params;
  };
  // `websocket` selects upgrade routes for a GET carrying "Upgrade: websocket".
  // Among several matching patterns the most literal wins ("/maps/import" over "/maps/{id}",
  // compared segment by segment from the left); ties go to the first added. With `websocket`, a
  // "WS" route is preferred and a plain GET route is the fallback.
  Match match(const std::string& method, const std::string& path, bool websocket = false) const;
  // The methods that have a route for `path` ("WS" reported as "GET"), sorted, for a 405's Allow.
  std::vector<std::string> allowedMethods(const std::string& path) const;
  const std::vector<Route>& routes() const { return routes_; }

 private:
  std::vector<Route> routes_;
  std::vector<std::vector<std::string>> segments_;  // each pattern split once, at add()
};

}  // namespace rover::http
