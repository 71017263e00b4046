#pragma once
// The body of a JSON route (defined in route_kit.cpp; apart from routes.hpp so that header declares
// nothing in rover::json).
#include <nlohmann/json.hpp>

#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"

namespace rover::api {

// Content-Type must be application/json (else 415 unsupported_media_type, field content-type: a
// cross-site text/plain post skips the CORS preflight); then parsed under `limits`.
nlohmann::json jsonBody(const http::Request& req, const rover::json::JsonLimits& limits);

}  // namespace rover::api
