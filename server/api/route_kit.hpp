#pragma once
// What the route files share (server/api/*_routes.cpp): the JSON media-type check, query
// parameters, listing pages, file responses, route docs, the "find it or 404" lookups and the
// JSON views of the stored resources.
#include <nlohmann/json.hpp>
#include <string>

#include "server/api/json_body.hpp"
#include "server/api/openapi.hpp"
#include "server/api/routes.hpp"
#include "server/http/http_types.hpp"
#include "server/store/database.hpp"

namespace rover::json {}

namespace rover::api {

// The names every route file uses, declared once here.
using http::ApiError;
using http::Request;
using http::Response;
using nlohmann::json;
using openapi::Operation;
using openapi::ref;
namespace rj = rover::json;

// The request's media type: Content-Type without its parameters, lower case, trimmed.
std::string mediaType(const http::Request& req);
// The one JSON media-type check: application/json (parameters such as charset allowed). A browser
// sends text/plain, form-urlencoded or multipart cross-site without asking first (no CORS
// preflight), so accepting those would let any page launch or rename missions on an open server.
bool sendsJson(const http::Request& req);

// ?key= as a finite number (400 invalid_parameter naming it), `fallback` when absent or empty.
double queryNumber(const http::Request& req, const std::string& key, double fallback);
// An integer query parameter in [lo, hi], range-checked as a double before the conversion (a
// static_cast<int> of 1e300 is undefined behaviour).
long long queryInteger(const http::Request& req, const std::string& key, long long fallback, long long lo,
                       long long hi);
// ?key= as given, "" when absent.
std::string queryString(const http::Request& req, const std::string& key);

// Listing pages: ?limit= (default 50, at most 500) and ?offset= (rows skipped). The body stays a
// JSON array; X-Total-Count holds the total and, when more rows follow, a Link header
// <path?limit=L&offset=O>; rel="next" (RFC 8288) points at the next page.
constexpr long long kDefaultPage = 50, kMaxPage = 500;
struct Page {
  long long limit, offset;
};
Page pageOf(const http::Request& req);
http::Response pageResponse(const http::Request& req, const Page& page, nlohmann::json items, long long total);

// A named handler of a route file; what it throws is answered by the error table (error_table.hpp).
using ApiHandler = http::Response (*)(ApiContext& ctx, const http::Request& req);
http::Handler handler(ApiContext& ctx, ApiHandler fn);

// A file answered from disk with its media type.
http::Response fileResponse(const std::string& path, const std::string& type);
// `r` offered as a download named `filename` (Content-Disposition: attachment).
http::Response withAttachment(http::Response r, const std::string& filename);

// `blocking`: the handler is slow (GDAL, rendering, PDM discretisation, whole-DEM validation)
// and runs on the server's work pool, so the io threads keep answering (see RouteOptions).
constexpr bool onPool = true;
// A string path or query parameter (an id) in OpenAPI.
extern const nlohmann::json kIdSchema;

// Invalidates a map's cached body when the write that changes it has finished, on success or
// failure (after, not before: see ApiContext::mapCacheTicket).
struct InvalidateMapAfter {
  ApiContext& ctx;
  std::string id;
  ~InvalidateMapAfter() { ctx.invalidateMap(id); }
};

// The new name a rename's body {"name", "version"?} holds (PATCH /api/maps/{id}, /api/studies/{id}):
// 400 bad_json (not an object), unknown_field (any other member), invalid_field naming `name` (not
// a string, breaks the name rule rj::checkName, or blank: a map or study is always named).
// The one member a rename may change (`key`, plus "version"), checked as a name; 400 naming it.
std::string renamedTo(const nlohmann::json& body, const std::string& key, bool blankAllowed);
std::string newNameOf(const nlohmann::json& body);

// The 404s of the stored resources, one wording each; `field` names the input that held the id.
http::ApiError mapNotFound(const std::string& id, const std::string& field);
http::ApiError missionNotFound(const std::string& id);
store::MapRecord mapOr404(ApiContext& ctx, const std::string& id, const std::string& field);
store::MissionRecord missionOr404(ApiContext& ctx, const std::string& id);

// The digest of a map's grid (maps/dem_digest): stored with maps imported since mission files,
// computed from the loaded grid for older ones.
std::string mapDigest(ApiContext& ctx, const std::string& mapId);

// Sends an event on the live stream (issue 26; server/streams/event_hub.hpp).
void publishEvent(ApiContext& ctx, const std::string& kind, const std::string& object, const std::string& id,
                  const std::string& map, long long version, const std::string& by);

// The JSON views of the stored resources, with their links.
nlohmann::json mapJson(const store::MapRecord& m);
// A map's tile grid (maps/tile_grid.hpp) for a tiled viewer: tile_size, zmin/zmax, native_zoom,
// resolutions (metres per tile pixel along x, one per zoom; resolutions_y along y), tile_counts
// ([across, down] per zoom), extent [0, 0, width_m, height_m] and origin (top-left) in the local
// frame, url (a template with {layer}, {z}, {x}, {y}).
nlohmann::json tileGridJson(const store::MapRecord& m);
// What a map's cell size and heights say about its use by a micro-rover (core/terrain/
// scale_check): [{code, field, message}], from the stored metadata, so maps stored before the
// check have it too.
nlohmann::json scaleWarningsJson(const nlohmann::json& meta);
nlohmann::json pdmJson(const store::PdmRecord& p);
nlohmann::json missionJson(const store::MissionRecord& m);

}  // namespace rover::api
