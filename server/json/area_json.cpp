#include "server/json/area_json.hpp"

#include <cmath>

#include "server/http/http_types.hpp"

namespace rover::json {

using http::ApiError;
using nlohmann::json;

namespace {

// Bounded before any conversion, like every coordinate a client sends (the map check follows).
constexpr double kMaxCoordinate = 1e9;

double coordinate(const json& v, const std::string& field) {
  if (!v.is_number()) throw ApiError(400, "invalid_field", field + " must be a number of metres", field);
  const double d = v.get<double>();
  if (!std::isfinite(d) || std::fabs(d) > kMaxCoordinate)
    throw ApiError(400, "invalid_field", field + " must be a finite number of metres with |value| <= 1e9", field);
  return d;
}

}  // namespace

MissionArea areaFromJson(const json& v, const std::string& field) {
  const std::string shape = "an object {\"bbox\": [x0, y0, x1, y1]} or {\"polygon\": [[x, y], ...]} "
                            "in the map's local frame (metres from its lower-left corner)";
  if (!v.is_object() || v.size() != 1 || !(v.contains("bbox") || v.contains("polygon")))
    throw ApiError(400, "invalid_field", field + " must be " + shape, field);
  if (v.contains("bbox")) {
    const json& b = v["bbox"];
    const std::string f = field + ".bbox";
    if (!b.is_array() || b.size() != 4)
      throw ApiError(400, "invalid_field", f + " must be [x0, y0, x1, y1] (metres, local frame)", f);
    double c[4];
    for (int i = 0; i < 4; ++i) c[i] = coordinate(b[i], f + "[" + std::to_string(i) + "]");
    if (!(c[2] > c[0] && c[3] > c[1]))
      throw ApiError(400, "invalid_field", f + ": x1 and y1 must be greater than x0 and y0", f);
    return rectangleArea(c[0], c[1], c[2], c[3]);
  }
  const json& p = v["polygon"];
  const std::string f = field + ".polygon";
  if (!p.is_array() || p.size() < 3 || p.size() > kMaxAreaVertices + 1)
    throw ApiError(400, "invalid_field",
                   f + " must be an array of 3 to " + std::to_string(kMaxAreaVertices) + " positions [x, y]", f);
  Ring ring;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::string fi = f + "[" + std::to_string(i) + "]";
    if (!p[i].is_array() || p[i].size() != 2) throw ApiError(400, "invalid_field", fi + " must be [x, y]", fi);
    ring.emplace_back(coordinate(p[i][0], fi), coordinate(p[i][1], fi));
  }
  MissionArea a = polygonArea(std::move(ring));
  if (a.outline.size() < 3 || a.outline.size() > kMaxAreaVertices)
    throw ApiError(400, "invalid_field",
                   f + " must hold 3 to " + std::to_string(kMaxAreaVertices) + " distinct vertices", f);
  return a;
}

json areaToJson(const MissionArea& a) {
  if (a.rectangle) {
    const auto lo = a.lo(), hi = a.hi();
    return {{"bbox", {lo.x(), lo.y(), hi.x(), hi.y()}}};
  }
  json ring = json::array();
  for (const auto& p : a.outline) ring.push_back({p.x(), p.y()});
  return {{"polygon", ring}};
}

json windowToJson(const PlanningWindow& w) {
  return {{"origin", {w.origin.x(), w.origin.y()}},
          {"row0", w.row0},
          {"col0", w.col0},
          {"rows", w.grid.rows},
          {"cols", w.grid.cols},
          {"cell_size_m", w.grid.cellWidth}};
}

}  // namespace rover::json
