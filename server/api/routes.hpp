#pragma once
// The REST + WebSocket API (issue: server): every route, its handler and its OpenAPI entry.
#include <string>

#include "core/planning/planner.hpp"
#include "server/api/map_catalog.hpp"
#include "server/http/router.hpp"
#include "server/missions/mission_manager.hpp"

namespace rover::api {

struct ApiContext {
  store::Database& db;
  store::DataDir& dir;
  MapCatalog& maps;
  missions::MissionManager& missions;
  const PlannerRegistry& planners;
  std::string version = "0.1.0";
};

// Registers every /api route on `router`.
void addApiRoutes(http::Router& router, ApiContext& ctx);
// The OpenAPI 3 document of the router's routes.
nlohmann::json openApiDocument(const http::Router& router, const std::string& version);

}  // namespace rover::api
