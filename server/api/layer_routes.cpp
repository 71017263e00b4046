// GET /api/maps/{id}/layers/{file}: a map's layers as PNG overviews, GeoTIFFs or raw float32.
#include "server/api/route_kit.hpp"

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
    auto map = ctx.maps.get(req.params.at("id"));
    const GridGeometry& g = map->dem.geometry();
    r.headers = {{"X-Rows", std::to_string(g.rows)}, {"X-Cols", std::to_string(g.cols)},
                 {"X-Cell-Width-M", std::to_string(g.cellWidth)}, {"X-Cell-Height-M", std::to_string(g.cellHeight)},
                 {"X-Nodata", "NaN"}, {"X-Byte-Order", "little-endian"}};
  }
  r.headers.emplace_back("Cache-Control", "max-age=3600");
  return r;
}

}  // namespace

void addLayerRoutes(http::Router& router, ApiContext& ctx) {
  router.add("GET", "/api/maps/{id}/layers/{file}", handler(ctx, getLayer),
             routeDoc("A layer (elevation|hillshade|slope|traversability|pdm) as .png (?max= overview), "
                      ".tif (GeoTIFF) or .f32 (raw little-endian float32, size in X-Rows/X-Cols); ?pdm=ID for pdm.",
                      openapi::Operation()
                          .query("max", {{"type", "integer"}, {"minimum", 0}, {"maximum", 16384}},
                                 "PNG overview: longest side rounded up to 256, 512, 1024, 2048 or 4096.")
                          .query("pdm", kIdSchema, "The PDM of a pdm layer (default: the newest).")
                          .returns(200, "The layer file.", nullptr, "image/png")
                          .returns(200, "The layer file.", nullptr, "image/tiff")
                          .returns(200, "The layer file.", nullptr, "application/octet-stream")
                          .errors({400, 404, 503, 507}),
                      onPool));
}

}  // namespace rover::api
