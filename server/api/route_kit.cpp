#include "server/api/route_kit.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include "maps/dem_digest.hpp"
#include "core/terrain/scale_check.hpp"
#include "maps/tile_grid.hpp"
#include "server/json/json_edge.hpp"

namespace rover::api {


const json kIdSchema = {{"type", "string"}};

std::string mediaType(const Request& req) {
  std::string type = req.header("content-type");
  type = type.substr(0, type.find(';'));
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
  while (!type.empty() && (type.back() == ' ' || type.back() == '\t')) type.pop_back();
  while (!type.empty() && (type.front() == ' ' || type.front() == '\t')) type.erase(0, 1);
  return type;
}

bool sendsJson(const Request& req) { return mediaType(req) == "application/json"; }

json jsonBody(const Request& req, const rj::JsonLimits& limits) {
  if (!sendsJson(req)) {
    const std::string type = mediaType(req);
    throw ApiError(415, "unsupported_media_type",
                   "send the body as JSON with Content-Type: application/json" +
                       (type.empty() ? std::string(" (the request has none)") : " (not " + rj::shown(type) + ")"),
                   "content-type");
  }
  return rj::parseJsonLimited(req.body, limits);
}

double queryNumber(const Request& req, const std::string& key, double fallback) {
  auto it = req.query.find(key);
  if (it == req.query.end() || it->second.empty()) return fallback;
  char* end = nullptr;
  double v = std::strtod(it->second.c_str(), &end);
  if (*end != '\0' || !std::isfinite(v))
    throw ApiError(400, "invalid_parameter", key + " must be a number", key);
  return v;
}

long long queryInteger(const Request& req, const std::string& key, long long fallback, long long lo, long long hi) {
  // Decimal digits only: a number parser would also take 0x10, 1e1 and " 5" for an integer.
  if (auto it = req.query.find(key); it != req.query.end() && !it->second.empty()) {
    const std::string& t = it->second;
    const std::size_t digits = t[0] == '-' || t[0] == '+' ? 1 : 0;
    if (t.size() == digits || t.find_first_not_of("0123456789", digits) != std::string::npos)
      throw ApiError(400, "invalid_parameter",
                     key + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", key);
  }
  const double v = queryNumber(req, key, static_cast<double>(fallback));
  if (v < static_cast<double>(lo) || v > static_cast<double>(hi) || std::trunc(v) != v)
    throw ApiError(400, "invalid_parameter",
                   key + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", key);
  return static_cast<long long>(v);
}

std::string queryString(const Request& req, const std::string& key) {
  auto it = req.query.find(key);
  return it == req.query.end() ? "" : it->second;
}

Page pageOf(const Request& req) {
  return {queryInteger(req, "limit", kDefaultPage, 1, kMaxPage), queryInteger(req, "offset", 0, 0, 1'000'000'000)};
}

Response pageResponse(const Request& req, const Page& page, json items, long long total) {
  const long long next = page.offset + static_cast<long long>(items.size());
  Response r = Response::json(200, items);
  r.headers.emplace_back("X-Total-Count", std::to_string(total));
  if (!items.empty() && next < total)
    r.headers.emplace_back("Link", "<" + req.path + "?limit=" + std::to_string(page.limit) +
                                       "&offset=" + std::to_string(next) + ">; rel=\"next\"");
  return r;
}

http::Handler handler(ApiContext& ctx, ApiHandler fn) {
  return [&ctx, fn](const Request& req) { return fn(ctx, req); };
}

Response fileResponse(const std::string& path, const std::string& type) {
  Response r;
  r.file = path;
  r.contentType = type;
  return r;
}

Response withAttachment(Response r, const std::string& filename) {
  r.headers.emplace_back("Content-Disposition", "attachment; filename=\"" + filename + "\"");
  return r;
}

std::string renamedTo(const json& body, const std::string& key, bool blankAllowed) {
  if (!body.is_object()) throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  for (const auto& item : body.items())
    if (item.key() != key && item.key() != "version")
      throw ApiError(400, "unknown_field", "only '" + key + "' can be changed, not '" + rj::shown(item.key()) + "'",
                     rj::shown(item.key()));
  auto value = body.find(key);
  if (value == body.end() || !value->is_string()) throw ApiError(400, "invalid_field", key + " must be a string", key);
  const std::string text = value->get<std::string>();
  rj::checkName(text, key);
  if (!blankAllowed && text.find_first_not_of(" \t") == std::string::npos)
    throw ApiError(400, "invalid_field", key + " must not be empty or blank", key);
  return text;
}

std::string newNameOf(const json& body) { return renamedTo(body, "name", false); }

ApiError mapNotFound(const std::string& id, const std::string& field) {
  return ApiError(404, "not_found", "no map '" + rj::shown(id) + "'", field);
}

ApiError missionNotFound(const std::string& id) {
  return ApiError(404, "not_found", "no mission '" + rj::shown(id) + "'", "id");
}

store::MapRecord mapOr404(ApiContext& ctx, const std::string& id, const std::string& field) {
  auto m = ctx.db.getMap(id);
  if (!m) throw mapNotFound(id, field);
  return std::move(*m);
}

store::MissionRecord missionOr404(ApiContext& ctx, const std::string& id) {
  auto m = ctx.db.getMission(id);
  if (!m) throw missionNotFound(id);
  return std::move(*m);
}

std::string mapDigest(ApiContext& ctx, const std::string& mapId) {
  if (auto rec = ctx.db.getMap(mapId); rec && rec->meta.contains("dem_sha256"))
    return rec->meta["dem_sha256"].get<std::string>();
  return maps::demSha256(ctx.maps.get(mapId)->dem);
}

json tileGridJson(const store::MapRecord& m) {
  const json& meta = m.meta;
  if (!meta.contains("rows") || !meta["rows"].is_number_integer() || !meta.contains("cols") ||
      !meta["cols"].is_number_integer() || !meta.contains("cell_size_m") || !meta["cell_size_m"].is_number())
    return nullptr;  // a record without its size (none is written so); the tiles still answer
  const int rows = meta["rows"].get<int>(), cols = meta["cols"].get<int>();
  const double cw = meta["cell_size_m"].get<double>();
  const double ch = meta.contains("cell_height_m") && meta["cell_height_m"].is_number() ? meta["cell_height_m"].get<double>() : cw;
  const maps::TileGrid g = maps::tileGridOf(rows, cols);
  json res = json::array(), resY = json::array(), counts = json::array();
  for (int z = 0; z <= g.maxZoom(); ++z) {
    const double f = std::ldexp(1.0, g.nativeZoom - z);  // cells per tile pixel
    res.push_back(cw * f);
    resY.push_back(ch * f);
    counts.push_back({maps::tilesAcross(g, z), maps::tilesDown(g, z)});
  }
  return {{"tile_size", maps::kTileSize},
          {"zmin", 0},
          {"zmax", g.maxZoom()},
          {"native_zoom", g.nativeZoom},
          {"resolutions", res},
          {"resolutions_y", resY},
          {"tile_counts", counts},
          {"extent", {0.0, 0.0, cols * cw, rows * ch}},
          {"origin", {0.0, rows * ch}},
          {"url", "/api/maps/" + m.id + "/tiles/{layer}/{z}/{x}/{y}.png"}};
}

json scaleWarningsJson(const json& meta) {
  auto number = [&](const char* key, const char* sub = nullptr) {
    const json* v = meta.contains(key) ? &meta[key] : nullptr;
    if (v && sub) v = v->is_object() && v->contains(sub) ? &(*v)[sub] : nullptr;
    return v && v->is_number() ? v->get<double>() : std::nan("");
  };
  const std::string body = meta.contains("body") && meta["body"].is_string() ? meta["body"].get<std::string>() : "";
  const terrain::Body b = body == "mars"    ? terrain::Body::Mars
                          : body == "moon"  ? terrain::Body::Moon
                          : body == "earth" ? terrain::Body::Earth
                                            : terrain::Body::Unknown;
  const double cw = number("cell_size_m");
  const double ch = std::isnan(number("cell_height_m")) ? cw : number("cell_height_m");
  json out = json::array();
  for (const auto& w : terrain::scaleWarnings(cw, ch, number("elevation", "min"), number("elevation", "max"), b))
    out.push_back({{"code", w.code}, {"field", w.field}, {"message", w.message}});
  return out;
}

json mapJson(const store::MapRecord& m) {
  json j = m.meta;
  j["id"] = m.id;
  j["name"] = m.name;
  j["created_at"] = m.createdAt;
  j["version"] = m.version;
  j["layers"] = json::object();
  for (const char* l : {"elevation", "hillshade", "slope", "traversability", "pdm"})
    j["layers"][l] = "/api/maps/" + m.id + "/layers/" + l + ".png";
  j["tiles"] = tileGridJson(m);
  j["warnings"] = scaleWarningsJson(m.meta);
  return j;
}

json pdmJson(const store::PdmRecord& p) {
  json j = p.meta;
  j["id"] = p.id;
  j["map"] = p.mapId;
  j["name"] = p.name;
  j["created_at"] = p.createdAt;
  j["version"] = p.version;
  // An edited PDM's links name its version, so a browser's cached overview is not shown for it.
  const std::string v = p.version > 1 ? "&v=" + std::to_string(p.version) : std::string();
  j["layer"] = "/api/maps/" + p.mapId + "/layers/pdm.png?pdm=" + p.id + v;
  j["raster"] = "/api/maps/" + p.mapId + "/layers/pdm.tif?pdm=" + p.id + v;
  return j;
}

json missionJson(const store::MissionRecord& m) {
  return {{"id", m.id},          {"map", m.mapId},          {"pdm", m.pdmId.empty() ? json(nullptr) : json(m.pdmId)},
          {"label", m.label}, {"version", m.version},
          {"map_name", m.mapName.empty() ? json(nullptr) : json(m.mapName)},
          {"pdm_name", m.pdmName.empty() ? json(nullptr) : json(m.pdmName)},
          {"planner", m.planner}, {"status", enumName(m.status)},      {"message", m.message},
          {"created_at", m.createdAt}, {"started_at", m.startedAt}, {"finished_at", m.finishedAt},
          {"metrics", m.metrics}, {"spec", m.spec},
          {"links",
           {{"stream", "/api/missions/" + m.id + "/stream"},
            {"result_json", "/api/missions/" + m.id + "/result.json"},
            {"result_geojson", "/api/missions/" + m.id + "/result.geojson"},
            {"result_csv", "/api/missions/" + m.id + "/result.csv"},
            {"map_png", "/api/missions/" + m.id + "/map.png"},
            {"map_tif", "/api/missions/" + m.id + "/map.tif"}}}};
}

void publishEvent(ApiContext& ctx, const std::string& kind, const std::string& object, const std::string& id,
                  const std::string& map, long long version, const std::string& by) {
  if (!ctx.events) return;
  streams::Event e;
  e.kind = kind;
  e.object = object;
  e.id = id;
  e.map = map;
  e.version = version;
  e.by = by;
  ctx.events->publish(std::move(e));
}

}  // namespace rover::api
