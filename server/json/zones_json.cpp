#include "server/json/zones_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"

namespace rover::json {

using http::ApiError;
using nlohmann::json;

namespace {

[[noreturn]] void refuse(const std::string& field, const std::string& why) {
  throw ApiError(400, "invalid_zones", field + ": " + why, field);
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Twice the signed area of a closed ring (shoelace).
double twiceArea(const Ring& ring) {
  double a = 0;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
    a += ring[j].x() * ring[i].y() - ring[i].x() * ring[j].y();
  return a;
}

}  // namespace

KeepOut zonesFromJson(const json& value, const std::string& prefix, const GridGeometry* map,
                      const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& toLocal) {
  if (!value.is_object()) refuse(prefix, "must be a GeoJSON FeatureCollection of Polygons");
  auto type = value.find("type");
  if (type == value.end() || *type != "FeatureCollection")
    refuse(prefix + ".type", "must be \"FeatureCollection\"");
  auto features = value.find("features");
  if (features == value.end() || !features->is_array())
    refuse(prefix + ".features", "must be an array of Polygon features");
  if (features->size() > kMaxZones)
    refuse(prefix + ".features", "at most " + std::to_string(kMaxZones) + " zones (got " +
                                     std::to_string(features->size()) + ")");
  KeepOut out;
  std::size_t vertices = 0;
  for (std::size_t f = 0; f < features->size(); ++f) {
    const std::string ff = prefix + ".features[" + std::to_string(f) + "]";
    const json& feature = (*features)[f];
    if (!feature.is_object() || feature.value("type", json()) != "Feature")
      refuse(ff, "must be a GeoJSON Feature");
    if (auto p = feature.find("properties"); p != feature.end() && !p->is_null()) {
      if (!p->is_object()) refuse(ff + ".properties", "must be an object or null");
      if (auto n = p->find("name"); n != p->end() && !n->is_null()) {
        if (!n->is_string()) refuse(ff + ".properties.name", "must be a string");
        checkName(n->get<std::string>(), ff + ".properties.name");
      }
    }
    auto geometry = feature.find("geometry");
    if (geometry == feature.end() || !geometry->is_object())
      refuse(ff + ".geometry", "must be a Polygon geometry");
    if (geometry->value("type", json()) != "Polygon")
      refuse(ff + ".geometry.type", "must be \"Polygon\"");
    const std::string fc = ff + ".geometry.coordinates";
    auto coords = geometry->find("coordinates");
    if (coords == geometry->end() || !coords->is_array() || coords->empty())
      refuse(fc, "must be an array of linear rings (the outline, then any holes)");
    Polygon polygon;
    for (std::size_t r = 0; r < coords->size(); ++r) {
      const json& ring = (*coords)[r];
      const std::string rf = "ring " + std::to_string(r);
      if (!ring.is_array() || ring.size() < 4)
        refuse(fc, rf + " must be an array of at least 4 positions (3 points and the first again)");
      if (vertices + ring.size() - 1 > kMaxZoneVertices)
        refuse(fc, "at most " + std::to_string(kMaxZoneVertices) + " vertices in all zones");
      Ring points;
      for (std::size_t i = 0; i < ring.size(); ++i) {
        const json& pos = ring[i];
        const std::string pf = rf + " position " + std::to_string(i);
        if (!pos.is_array() || pos.size() < 2 || pos.size() > 3 || !pos[0].is_number() ||
            !pos[1].is_number())
          refuse(fc, pf + " must be [x, y] (numbers)");
        Eigen::Vector2d v(pos[0].get<double>(), pos[1].get<double>());
        if (!v.allFinite() || std::abs(v.x()) > 1e9 || std::abs(v.y()) > 1e9)
          refuse(fc, pf + " must be finite numbers with |v| <= 1e9");
        if (toLocal) {
          v = toLocal(v);
          if (!v.allFinite()) refuse(fc, pf + " cannot be converted to the map's local frame");
        }
        points.push_back(v);
      }
      if ((points.front() - points.back()).norm() > 1e-9 * std::max(1.0, points.front().norm()))
        refuse(fc, rf + " is not closed: its last position must repeat its first");
      points.pop_back();
      Ring distinct;
      for (const auto& p : points)
        if (std::none_of(distinct.begin(), distinct.end(), [&](const Eigen::Vector2d& d) { return d == p; }))
          distinct.push_back(p);
      if (distinct.size() < 3) refuse(fc, rf + " needs at least 3 distinct points");
      if (std::abs(twiceArea(points)) <= 1e-12) refuse(fc, rf + " has no area (its points are on one line)");
      vertices += points.size();
      polygon.push_back(std::move(points));
    }
    out.zones.push_back(std::move(polygon));
  }
  if (map) checkZonesOnMap(out, *map, prefix);
  return out;
}

std::vector<std::string> zoneNames(const json& value) {
  std::vector<std::string> out;
  if (!value.is_object() || !value.contains("features") || !value["features"].is_array()) return out;
  for (const json& f : value["features"]) {
    std::string name;
    if (f.is_object() && f.contains("properties") && f["properties"].is_object() &&
        f["properties"].contains("name") && f["properties"]["name"].is_string())
      name = f["properties"]["name"].get<std::string>();
    out.push_back(name);
  }
  return out;
}

void checkZonesOnMap(const KeepOut& zones, const GridGeometry& map, const std::string& prefix) {
  const double w = map.widthMetres(), h = map.heightMetres();
  const double slack = kZoneSlack * std::max(w, h);
  for (std::size_t z = 0; z < zones.zones.size(); ++z) {
    const std::string fc = prefix + ".features[" + std::to_string(z) + "].geometry.coordinates";
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
    for (const Ring& ring : zones.zones[z])
      for (const auto& v : ring) {
        if (v.x() < -slack || v.y() < -slack || v.x() > w + slack || v.y() > h + slack)
          refuse(fc, "vertex (" + num(v.x()) + ", " + num(v.y()) + ") m is off the map (" + num(w) +
                         " × " + num(h) + " m, local frame: metres from its lower-left corner)");
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
    if (hi.x() <= 0 || hi.y() <= 0 || lo.x() >= w || lo.y() >= h)
      refuse(fc, "the zone lies wholly outside the map");
  }
}

json zonesToJson(const KeepOut& zones, const std::vector<std::string>& names) {
  json features = json::array();
  for (std::size_t z = 0; z < zones.zones.size(); ++z) {
    json rings = json::array();
    for (const Ring& ring : zones.zones[z]) {
      json positions = json::array();
      for (const auto& v : ring) positions.push_back({v.x(), v.y()});
      if (!ring.empty()) positions.push_back({ring.front().x(), ring.front().y()});
      rings.push_back(std::move(positions));
    }
    json props = json::object();
    if (z < names.size() && !names[z].empty()) props["name"] = names[z];
    features.push_back({{"type", "Feature"},
                        {"properties", props},
                        {"geometry", {{"type", "Polygon"}, {"coordinates", rings}}}});
  }
  return {{"type", "FeatureCollection"}, {"features", features}};
}

}  // namespace rover::json
