#pragma once
// A map's keep-out zones (issue 13): GET|PUT /api/maps/{id}/zones.
#include "server/api/routes.hpp"

namespace rover::api {


void addZoneRoutes(http::Router& router, ApiContext& ctx);

}  // namespace rover::api
