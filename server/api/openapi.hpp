#pragma once
// The OpenAPI 3.0.3 document of the API (GET /api/openapi.json), complete enough to generate a
// client from: every route with its parameters, request body, success status and schema, and
// the errors it answers (all in the Error schema). The schemas that describe input are built
// from the tables the validation itself reads (each planner's ParamTable, the DEM import
// options, the mission request's limits), so a new parameter or limit shows up here by itself.
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/planning/planner.hpp"
#include "server/http/router.hpp"

namespace rover::api::openapi {

// {"$ref": "#/components/schemas/NAME"}.
nlohmann::json ref(const std::string& name);
// The JSON schema of one planner parameter: type, range or choices, default, doc and unit.
nlohmann::json paramSchema(const ParamInfo& info);

// What a route adds to its OpenAPI operation (kept in RouteOptions::openapi). Chainable:
//   Operation().body(ref("MissionRequest")).returns(202, "Queued", ref("Mission")).errors({404, 409})
class Operation {
 public:
  Operation& returns(int status, const std::string& description, nlohmann::json schema = nullptr,
                     const std::string& contentType = "application/json");
  // A response header of the last added status.
  Operation& header(const std::string& name, const std::string& type, const std::string& description);
  Operation& body(nlohmann::json schema, const std::string& contentType = "application/json");
  Operation& query(const std::string& name, nlohmann::json schema, const std::string& description,
                   bool required = false);
  // The If-Match request header (preconditions.hpp): the version the write was read at.
  Operation& ifMatch();
  // The ETag response header ("v<N>") of the last added status.
  Operation& etag();
  // Error statuses besides the ones every route may answer (401 with a token, 500).
  Operation& errors(std::initializer_list<int> statuses);
  // ?limit=&offset=, X-Total-Count and Link on the 200 of a listing of `item`.
  Operation& listing(const std::string& item);
  nlohmann::json toJson() const { return op_; }

 private:
  nlohmann::json op_ = nlohmann::json::object();
  int last_ = 0;
};

// The component schemas (server/api/openapi_schemas.cpp): Error, the resources, the mission
// request, each planner's parameters (from `planners`' tables), and studySchemas().
nlohmann::json componentSchemas(const PlannerRegistry& planners);

// The schemas of /api/studies (server/api/openapi_studies.cpp): Study, StudyDetail, StudySummary,
// StudyConfiguration, StudyPreset, StudyRun.
nlohmann::json studySchemas();

// The schemas of issue 26 (server/api/openapi_collab.cpp): Zone, ZoneDeleted, VersionConflict,
// Event, EventMessage, History, HistoryEntry, PdmChange; `zoneFeature` is the Zones' feature.
nlohmann::json collabSchemas(const nlohmann::json& zoneFeature);
// The messages of WS /api/events (each event's fields, their kinds and objects).
nlohmann::json eventMessageSchema();

// The document of every route of `router`; the planners' parameter tables and presets give the
// mission request's and planner listing's schemas.
nlohmann::json document(const http::Router& router, const PlannerRegistry& planners,
                        const std::string& version);

}  // namespace rover::api::openapi
