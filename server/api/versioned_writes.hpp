#pragma once
// The versioned writes the history's restore shares with the routes that own them (issue 26):
// each takes ApiContext::versionedWrites, checks the version named (412 with the current object
// when stale), writes one version more with its history entry, and tells the event stream.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/pdm/pdm.hpp"
#include "server/api/routes.hpp"
#include "server/http/http_types.hpp"
#include "server/store/database.hpp"

namespace rover::api {

// pdm_routes.cpp: a PDM's name and (Gaussian PDMs) components.
http::Response savePdm(ApiContext& ctx, const http::Request& req, const store::PdmRecord& p, const std::string& name,
                       const std::optional<std::vector<pdm::Gaussian>>& comps, long long expected);
std::string pdmWhat(const store::PdmRecord& p);

// zone_routes.cpp: a map's whole zone set (`stored`: validated, local frame; a feature's "id"
// keeps that zone's identity when the set holds it). `named`: the set's version the request
// named (none: only a first save). `restoring`: ids the set no longer holds come back as they were.
http::Response saveZoneSet(ApiContext& ctx, const http::Request& req, const std::string& mapId, nlohmann::json stored,
                           std::optional<long long> named, bool restoring);

}  // namespace rover::api
