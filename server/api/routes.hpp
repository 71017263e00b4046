#pragma once
// The REST + WebSocket API (issue: server): its shared context and the route files that register
// every route, its named handler and its OpenAPI entry.
#include <cstdint>
#include <mutex>
#include <string>
#include <unordered_map>

#include "core/planning/planner.hpp"
#include "server/api/map_catalog.hpp"
#include "server/api/openapi.hpp"
#include "server/http/router.hpp"
#include "server/missions/mission_manager.hpp"
#include "server/streams/event_hub.hpp"
#include "server/studies/study_manager.hpp"

namespace rover::api {

struct ApiContext {
  ApiContext(store::Database& d, store::DataDir& dd, MapCatalog& m, missions::MissionManager& mm,
             const PlannerRegistry& p)
      : db(d), dir(dd), maps(m), missions(mm), planners(p) {}
  store::Database& db;
  store::DataDir& dir;
  MapCatalog& maps;
  missions::MissionManager& missions;
  const PlannerRegistry& planners;
  studies::StudyManager* studies = nullptr;  // null: no /api/studies routes
  std::string version = "0.1.0";
  // Maps of more cells than this plan only in a mission area (issue 24; core/planning/
  // mission_area.hpp states the default and why); tests lower it to keep their maps small.
  std::int64_t wholeMapCells = kWholeMapCells;
  // The live event stream (issue 26): made by addApiRoutes when not set, its numbering continued
  // from the database.
  std::shared_ptr<streams::EventHub> events;
  // Versioned writes (zones, PDM edits, labels) and their events happen one at a time, so the
  // events of one object always come in version order. They are small and rare.
  std::mutex versionedWrites;

  // Serialized GET /api/maps/{id} bodies: the hottest read, changed only by the writes below.
  // Writers call invalidateMap *after* their write. A reader takes a ticket before it reads the
  // database and caches its body only if no invalidation happened since, so a GET racing a
  // delete cannot put the deleted map back into the cache.
  // The version goes with the body: the ETag of a cached answer (issue 26).
  struct CachedMapBody {
    std::string body;
    long long version = 1;
  };
  std::mutex mapCacheMutex;
  std::unordered_map<std::string, CachedMapBody> mapBodyCache;
  std::uint64_t mapCacheGeneration = 0;
  void invalidateMap(const std::string& id) {
    std::lock_guard lock(mapCacheMutex);
    ++mapCacheGeneration;
    mapBodyCache.erase(id);
  }
  std::uint64_t mapCacheTicket() {
    std::lock_guard lock(mapCacheMutex);
    return mapCacheGeneration;
  }
  // Stores `body` unless an invalidation came after `ticket`; returns whether it did.
  bool cacheMapBody(const std::string& id, std::string body, long long version, std::uint64_t ticket) {
    std::lock_guard lock(mapCacheMutex);
    if (ticket != mapCacheGeneration) return false;
    mapBodyCache[id] = CachedMapBody{std::move(body), version};
    return true;
  }
};

// Registers every /api route on `router` (the study routes too when ctx.studies is set).
void addApiRoutes(http::Router& router, ApiContext& ctx);
// A route's summary and OpenAPI operation (server/api/openapi.hpp: its statuses and schemas).
http::RouteOptions routeDoc(const std::string& summary, const openapi::Operation& op,
                            bool blocking = false);

// The route files, one per resource (addZoneRoutes: zone_routes.hpp).
void addPlannerRoutes(http::Router& router, ApiContext& ctx);  // GET /api/planners
void addMapRoutes(http::Router& router, ApiContext& ctx);      // /api/maps, /api/maps/{id}
void addLayerRoutes(http::Router& router, ApiContext& ctx);    // /api/maps/{id}/layers/{file}
void addPdmRoutes(http::Router& router, ApiContext& ctx);      // /api/maps/{id}/pdms...
void addMissionRoutes(http::Router& router, ApiContext& ctx);  // /api/missions...
void addStudyRoutes(http::Router& router, ApiContext& ctx);    // /api/studies...
void addEventRoutes(http::Router& router, ApiContext& ctx);    // WS /api/events
void addHistoryRoutes(http::Router& router, ApiContext& ctx);  // .../history, .../restore

}  // namespace rover::api
