// GET /api/maps/{id}/layers/{file}: a map's layers as PNG overviews, GeoTIFFs or raw float32.
#include <algorithm>
#include <cctype>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "maps/tile_grid.hpp"
#include "server/api/route_kit.hpp"
#include "server/store/data_dir.hpp"

namespace rover::api {


namespace {

Response getLayer(ApiContext& ctx, const Request& req) {
  const std::string file = req.params.at("file");
  auto dot = file.rfind('.');
  if (dot == std::string::npos) throw ApiError(404, "not_found", "layer files are NAME.png|tif|f32", "file");
  const std::string layer = file.substr(0, dot), format = file.substr(dot + 1);
  // Range-checked before the conversion; the catalog narrows it to the sizes it renders.
  const int max = static_cast<int>(queryInteger(req, "max", 0, 0, 1'000'000));
  std::string path = ctx.maps.layerFile(req.params.at("id"), layer, format, max, queryString(req, "pdm"));
  Response r = fileResponse(path, format == "png" ? "image/png" : format == "tif" ? "image/tiff" : "application/octet-stream");
  if (format == "f32") {
    const GridGeometry g = ctx.maps.header(req.params.at("id")).geometry;  // the map itself is not loaded
    r.headers = {{"X-Rows", std::to_string(g.rows)}, {"X-Cols", std::to_string(g.cols)},
                 {"X-Cell-Width-M", std::to_string(g.cellWidth)}, {"X-Cell-Height-M", std::to_string(g.cellHeight)},
                 {"X-Nodata", "NaN"}, {"X-Byte-Order", "little-endian"}};
  }
  r.headers.emplace_back("Cache-Control", "max-age=3600");
  return r;
}

// A tile address number: 1 to 9 decimal digits (anything else names no tile: 404, never a 500 or
// an overflow).
long long tileNumber(const std::string& s, const char* field) {
  if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); }))
    throw ApiError(404, "not_found", std::string("a tile's ") + field + " is a number of decimal digits", "tile");
  return std::stoll(s);
}

// Tiles of a map never change (a map is immutable; a PDM tile names its PDM), so the ETag is the
// address itself with the renderer's version (MapCatalog::kTileVersion).

// Whether If-None-Match names `etag` (RFC 9110 §13.1.2): "*" alone, or a comma-separated list of
// entity tags, each compared weakly (a W/ prefix ignored). Anything else matches nothing.
bool etagMatches(const std::string& ifNoneMatch, const std::string& etag) {
  auto trim = [](std::string_view s) {
    const auto a = s.find_first_not_of(" \t");
    if (a == std::string_view::npos) return std::string_view();
    return s.substr(a, s.find_last_not_of(" \t") - a + 1);
  };
  const std::string_view all = trim(ifNoneMatch);
  if (all == "*") return true;
  std::size_t from = 0;
  while (from <= all.size()) {
    const std::size_t comma = std::min(all.find(',', from), all.size());
    std::string_view tag = trim(all.substr(from, comma - from));
    if (tag.substr(0, 2) == "W/") tag.remove_prefix(2);
    if (tag == etag) return true;
    from = comma + 1;
  }
  return false;
}

// A tile's address as the request names it: /tiles/{layer}/{z}/{x}/{y}.{format}[?pdm=ID].
struct TileAddress {
  std::string id, layer, format, pdm;
  long long z = 0, x = 0, y = 0;
};

TileAddress tileAddress(const Request& req) {
  TileAddress a;
  a.id = req.params.at("id");
  a.layer = req.params.at("layer");
  const std::string& last = req.params.at("y");
  const auto dot = last.find('.');
  if (dot == std::string::npos) throw ApiError(404, "not_found", "a tile is Y.png or Y.f32", "tile");
  a.format = last.substr(dot + 1);
  a.z = tileNumber(req.params.at("z"), "zoom");
  a.x = tileNumber(req.params.at("x"), "column");
  a.y = tileNumber(last.substr(0, dot), "row");
  a.pdm = queryString(req, "pdm");
  return a;
}

// `pdmTag`: a pdm tile's PDM and version ("" for the map's own layers).
std::string tileEtag(const TileAddress& a, const std::string& pdmTag) {
  // Appended piece by piece: GCC 12's -Wrestrict misreads a chain of operator+ here.
  std::string etag = "\"";
  for (const std::string& part : {std::string(MapCatalog::kTileVersion), a.id, a.layer, pdmTag,
                                  std::to_string(a.z), std::to_string(a.x)}) {
    if (part.empty()) continue;
    etag += part;
    etag += '-';
  }
  etag += std::to_string(a.y);
  etag += '.';
  etag += a.format;
  etag += '"';
  return etag;
}

const char* tileType(const TileAddress& a) { return a.format == "png" ? "image/png" : "application/octet-stream"; }

// A tile's answer from its body (set by the caller unless 304): status, validators and caching.
Response tileResponse(Response r, const TileAddress& a, const std::string& etag) {
  r.headers.emplace_back("ETag", etag);
  r.headers.emplace_back("Cache-Control", a.layer == "pdm" ? "no-cache" : "public, max-age=31536000, immutable");
  if (a.format == "f32")
    r.headers.insert(r.headers.end(), {{"X-Rows", std::to_string(maps::kTileSize)},
                                       {"X-Cols", std::to_string(maps::kTileSize)},
                                       {"X-Nodata", "NaN"}, {"X-Byte-Order", "little-endian"}});
  return r;
}

// A tile file is at most a 256² float32 tile (256 KiB) or an RGBA PNG a little over it.
constexpr std::uint64_t kMaxTileBytes = 1 << 20;

// The io thread's answer for a tile already made (RouteOptions::quick): 304, or the file's bytes
// when the page cache holds them (read whole, so header and body leave in one write). Anything
// else (not made, a pdm tile, the file evicted meanwhile or on disk only) goes to the pool's getTile.
std::optional<Response> warmTile(ApiContext& ctx, const Request& req) {
  const TileAddress a = tileAddress(req);
  const auto path = ctx.maps.madeTile(a.id, a.layer, a.format, a.z, a.x, a.y);
  if (!path) return std::nullopt;
  const std::string etag = tileEtag(a, "");
  Response r;
  if (etagMatches(req.header("if-none-match"), etag)) {
    r.status = 304;
  } else {
    auto bytes = store::DataDir::readFileUpTo(*path, kMaxTileBytes, store::DataDir::Read::CachedOnly);
    if (!bytes || bytes->empty()) return std::nullopt;  // a tile is never empty
    r.contentType = tileType(a);
    r.body = std::move(*bytes);
  }
  return tileResponse(std::move(r), a, etag);
}

Response getTile(ApiContext& ctx, const Request& req) {
  const TileAddress a = tileAddress(req);
  MapCatalog::Tile tile = ctx.maps.tileFile(a.id, a.layer, a.format, a.z, a.x, a.y, a.pdm);  // 404s checked first
  // A file made earlier is read now: the cache may evict it (or an edit discard an old PDM
  // version's) between the lookup and the read; then it is asked for once more, which makes it anew.
  for (int attempt = 0; tile.made.empty(); ++attempt) {
    if (auto bytes = store::DataDir::readFileUpTo(tile.path, kMaxTileBytes); bytes && !bytes->empty())
      tile.made = std::move(*bytes);
    else if (attempt == 0)
      tile = ctx.maps.tileFile(a.id, a.layer, a.format, a.z, a.x, a.y, a.pdm);
    else
      throw std::runtime_error("tile file " + tile.path + " gone again after it was made");  // 500, logged
  }
  // A PDM can be edited (issue 26): its tiles name its version, and are revalidated (ETag) rather
  // than kept a year.
  std::string pdmTag;
  if (a.layer == "pdm") pdmTag = a.pdm + tile.pdmVersion;  // the version drawn, not one edited since
  const std::string etag = tileEtag(a, pdmTag);
  Response r;
  if (etagMatches(req.header("if-none-match"), etag)) {
    r.status = 304;
  } else {
    r.contentType = tileType(a);
    r.body = std::move(tile.made);
  }
  return tileResponse(std::move(r), a, etag);
}

}  // namespace

void addLayerRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/maps/{id}/layers/{file}", handler(ctx, getLayer),
             routeDoc("A layer (elevation|hillshade|slope|traversability|pdm) as .png (?max= overview), "
                      ".tif (GeoTIFF) or .f32 (raw little-endian float32, size in X-Rows/X-Cols); ?pdm=ID for pdm. "
                      "On a map over 25 M cells, elevation.tif and traversability.tif are its stored files, "
                      "slope/hillshade .tif and elevation/slope/hillshade .f32 are computed band by band (an .f32 "
                      "up to a quarter of the layer cache, 256 MiB by default), and full-size .png, "
                      "traversability.f32 and pdm files → 413. "
                      "elevation.tif of such a map still stored raw (its COG being written) → 503 with Retry-After.",
                      openapi::Operation()
                          .query("max", {{"type", "integer"}, {"minimum", 0}, {"maximum", 16384}},
                                 "PNG overview: longest side rounded up to 256, 512, 1024, 2048 or 4096.")
                          .query("pdm", kIdSchema, "The PDM of a pdm layer (default: the newest).")
                          .returns(200, "The layer file.", nullptr, "image/png")
                          .returns(200, "The layer file.", nullptr, "image/tiff")
                          .returns(200, "The layer file.", nullptr, "application/octet-stream")
                          .errors({400, 404, 409, 413, 503, 507}),
                      onPool));
  http::RouteOptions tiles =
      routeDoc("A 256-px tile of a layer on the map's tile grid (the map's tiles: size, zmax, "
               "resolutions, extent): .png for every layer, .f32 (256×256 little-endian float32, NaN "
               "for no data and beyond the map) for elevation and slope; ?pdm=ID for pdm. Tiles never "
               "change: ETag, Cache-Control immutable, If-None-Match → 304. An address outside the grid → 404.",
               openapi::Operation()
                   .query("pdm", kIdSchema, "The PDM of a pdm tile (required for pdm).")
                   .returns(200, "The tile.", nullptr, "image/png")
                   .header("ETag", "string", "The tile's version (constant for the tile).")
                   .header("Cache-Control", "string", "public, max-age=31536000, immutable")
                   .returns(200, "The tile.", nullptr, "application/octet-stream")
                   .returns(304, "Not modified: If-None-Match named the tile's ETag.")
                   .errors({400, 404, 409, 503, 507}),
               onPool);
  // A tile already made is answered on the io thread; the pool only renders.
  tiles.quick = [&ctx](const Request& req) { return warmTile(ctx, req); };
  router.add("GET", "/api/maps/{id}/tiles/{layer}/{z}/{x}/{y}", handler(ctx, getTile), std::move(tiles));
}

}  // namespace rover::api
