#pragma once
// The REST + WebSocket API (issue: server): every route, its handler and its OpenAPI entry.
#include <mutex>
#include <string>
#include <unordered_map>

#include "core/planning/planner.hpp"
#include "server/api/map_catalog.hpp"
#include "server/http/router.hpp"
#include "server/missions/mission_manager.hpp"

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
  std::string version = "0.1.0";

  // Serialized GET /api/maps/{id} bodies: the hottest read, changed only by the writes below.
  std::mutex mapCacheMutex;
  std::unordered_map<std::string, std::string> mapBodyCache;
  void invalidateMap(const std::string& id) {
    std::lock_guard lock(mapCacheMutex);
    mapBodyCache.erase(id);
  }
};

// Registers every /api route on `router`.
void addApiRoutes(http::Router& router, ApiContext& ctx);
// The OpenAPI 3 document of the router's routes.
nlohmann::json openApiDocument(const http::Router& router, const std::string& version);

}  // namespace rover::api
