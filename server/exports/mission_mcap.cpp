#include "server/exports/mission_mcap.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <fcntl.h>
#include <unistd.h>
#include <cmath>
#include <cstring>
#include <ostream>
#include <streambuf>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "core/planning/ground_sample.hpp"
#include "maps/lon_lat.hpp"
#include "server/store/data_dir.hpp"

namespace rover::exports {

using nlohmann::json;

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// ---- JSON text for the many small messages (pose, fix, telemetry: ~3 per 10 Hz sample) --------
// Written by hand with std::to_chars (locale-free, shortest for the decimals asked): nlohmann's
// 17-digit doubles would double the file for millimetre positions.

void putNumber(std::string& s, double v, int decimals) {
  if (!std::isfinite(v)) {
    s += "null";  // never for a required field: callers check first
    return;
  }
  if (v == 0) v = 0;  // no "-0"
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));
  // Trailing zeros and a bare point add nothing: "1.500000" -> "1.5", "2.000" -> "2".
  if (text.find('.') != std::string_view::npos) {
    while (text.back() == '0') text.remove_suffix(1);
    if (text.back() == '.') text.remove_suffix(1);
  }
  if (text == "-0") text = "0";
  s += text;
}

void putTime(std::string& s, std::uint64_t ns) {
  s += "{\"sec\":" + std::to_string(ns / 1000000000ULL) + ",\"nsec\":" + std::to_string(ns % 1000000000ULL) + "}";
}

json timeJson(std::uint64_t ns) { return {{"sec", ns / 1000000000ULL}, {"nsec", ns % 1000000000ULL}}; }

std::uint64_t toNs(double seconds) {
  if (!std::isfinite(seconds) || seconds <= 0) return 0;
  return static_cast<std::uint64_t>(std::llround(seconds * 1e9));
}

std::string base64(const unsigned char* p, std::size_t n) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < n; i += 3) {
    const unsigned v = (p[i] << 16) | (p[i + 1] << 8) | p[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < n) {
    const unsigned v = (p[i] << 16) | (i + 1 < n ? p[i + 1] << 8 : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < n ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// ---- Schemas: Foxglove's well-known ones (docs.foxglove.dev "Message schemas"), as JSON Schema --
// The field names, types and enum values are Foxglove's; the documents are written here, reduced
// to what a reader needs to parse the messages.

json num() { return {{"type", "number"}}; }
json integer() { return {{"type", "integer"}}; }
json str() { return {{"type", "string"}}; }
json object(json properties) { return {{"type", "object"}, {"properties", std::move(properties)}}; }
json arrayOf(json items) { return {{"type", "array"}, {"items", std::move(items)}}; }
json timeSchema() {
  return {{"type", "object"}, {"title", "time"},
          {"properties", {{"sec", {{"type", "integer"}, {"minimum", 0}}},
                          {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}}}};
}
json vector3() { return object({{"x", num()}, {"y", num()}, {"z", num()}}); }
json quaternion() { return object({{"x", num()}, {"y", num()}, {"z", num()}, {"w", num()}}); }
json poseSchema() { return object({{"position", vector3()}, {"orientation", quaternion()}}); }
json color() { return object({{"r", num()}, {"g", num()}, {"b", num()}, {"a", num()}}); }
// An enum as Foxglove's JSON schemas give it: an integer, one of the named constants.
json enumOf(const std::string& title, const std::vector<std::pair<std::string, int>>& values) {
  json oneOf = json::array();
  for (const auto& [name, v] : values) oneOf.push_back({{"title", name}, {"const", v}});
  return {{"title", title}, {"oneOf", oneOf}};
}
json document(const std::string& title, json properties) {
  json d = object(std::move(properties));
  d["title"] = title;
  d["$schema"] = "https://json-schema.org/draft/2020-12/schema";
  return d;
}

json poseInFrameSchema() {
  return document("foxglove.PoseInFrame", {{"timestamp", timeSchema()}, {"frame_id", str()}, {"pose", poseSchema()}});
}
json locationFixSchema() {
  return document("foxglove.LocationFix",
                  {{"timestamp", timeSchema()}, {"frame_id", str()}, {"latitude", num()}, {"longitude", num()},
                   {"altitude", num()}, {"position_covariance", {{"type", "array"}, {"items", num()}, {"minItems", 9}, {"maxItems", 9}}},
                   {"position_covariance_type",
                    enumOf("foxglove.PositionCovarianceType", {{"UNKNOWN", 0}, {"APPROXIMATED", 1}, {"DIAGONAL_KNOWN", 2}, {"KNOWN", 3}})}});
}
json gridSchema() {
  json field = object({{"name", str()}, {"offset", integer()},
                       {"type", enumOf("foxglove.NumericType", {{"UNKNOWN", 0}, {"UINT8", 1}, {"INT8", 2}, {"UINT16", 3}, {"INT16", 4},
                                                                {"UINT32", 5}, {"INT32", 6}, {"FLOAT32", 7}, {"FLOAT64", 8}})}});
  return document("foxglove.Grid",
                  {{"timestamp", timeSchema()}, {"frame_id", str()}, {"pose", poseSchema()}, {"column_count", integer()},
                   {"cell_size", object({{"x", num()}, {"y", num()}})}, {"row_stride", integer()}, {"cell_stride", integer()},
                   {"fields", arrayOf(field)}, {"data", {{"type", "string"}, {"contentEncoding", "base64"}}}});
}
json sceneUpdateSchema() {
  json line = object({{"type", enumOf("foxglove.LineType", {{"LINE_STRIP", 0}, {"LINE_LOOP", 1}, {"LINE_LIST", 2}})},
                      {"pose", poseSchema()}, {"thickness", num()}, {"scale_invariant", {{"type", "boolean"}}},
                      {"points", arrayOf(vector3())}, {"color", color()}, {"colors", arrayOf(color())},
                      {"indices", arrayOf(integer())}});
  json sphere = object({{"pose", poseSchema()}, {"size", vector3()}, {"color", color()}});
  json entity = object({{"timestamp", timeSchema()}, {"frame_id", str()}, {"id", str()},
                        {"lifetime", object({{"sec", integer()}, {"nsec", integer()}})}, {"frame_locked", {{"type", "boolean"}}},
                        {"metadata", arrayOf(object({{"key", str()}, {"value", str()}}))},
                        {"arrows", arrayOf(object({}))}, {"cubes", arrayOf(object({}))}, {"spheres", arrayOf(sphere)},
                        {"cylinders", arrayOf(object({}))}, {"lines", arrayOf(line)}, {"triangles", arrayOf(object({}))},
                        {"texts", arrayOf(object({}))}, {"models", arrayOf(object({}))}});
  return document("foxglove.SceneUpdate",
                  {{"deletions", arrayOf(object({{"timestamp", timeSchema()}, {"type", integer()}, {"id", str()}}))},
                   {"entities", arrayOf(entity)}});
}
json logSchema() {
  return document("foxglove.Log",
                  {{"timestamp", timeSchema()},
                   {"level", enumOf("foxglove.LogLevel", {{"UNKNOWN", 0}, {"DEBUG", 1}, {"INFO", 2}, {"WARNING", 3}, {"ERROR", 4}, {"FATAL", 5}})},
                   {"message", str()}, {"name", str()}, {"file", str()}, {"line", integer()}});
}
json telemetrySchema() {
  json d = document("roverplan.RoverTelemetry",
                    {{"timestamp", timeSchema()}, {"rover", integer()},
                     {"pitch_deg", num()}, {"roll_deg", num()}, {"heading_deg", num()},
                     {"speed_m_s", num()}, {"energy_j", num()}, {"elevation_m", num()}});
  d["description"] = "A rover's attitude (pitch, roll, heading, degrees), speed over the ground, energy used since "
                     "the start (paper 000 eq. 5) and the terrain height under it; absent when the planner does not know it.";
  return d;
}

// ---- Scene --------------------------------------------------------------------------------------

json point(const Eigen::Vector2d& p) { return {{"x", p.x()}, {"y", p.y()}, {"z", 0.0}}; }
json rgba(double r, double g, double b, double a = 1.0) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }
json identityPose() { return {{"position", {{"x", 0.0}, {"y", 0.0}, {"z", 0.0}}}, {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", 0.0}, {"w", 1.0}}}}; }

// The colour of rover k: the page's palette order (a few distinct hues, repeated).
json roverColor(int k) {
  static constexpr double kPalette[][3] = {{0.90, 0.30, 0.24}, {0.20, 0.60, 0.86}, {0.18, 0.80, 0.44}, {0.95, 0.77, 0.06},
                                           {0.61, 0.35, 0.71}, {0.90, 0.49, 0.13}, {0.10, 0.74, 0.61}, {0.93, 0.44, 0.71}};
  const auto& c = kPalette[static_cast<std::size_t>(k) % std::size(kPalette)];
  return rgba(c[0], c[1], c[2]);
}

json entity(const std::string& id, json lines, json spheres, json metadata) {
  return {{"timestamp", timeJson(0)}, {"frame_id", "map"}, {"id", id}, {"lifetime", {{"sec", 0}, {"nsec", 0}}},
          {"frame_locked", true}, {"metadata", std::move(metadata)}, {"arrows", json::array()}, {"cubes", json::array()},
          {"spheres", std::move(spheres)}, {"cylinders", json::array()}, {"lines", std::move(lines)},
          {"triangles", json::array()}, {"texts", json::array()}, {"models", json::array()}};
}

json line(int type, const std::vector<Eigen::Vector2d>& pts, double thickness, json color) {
  json points = json::array();
  for (const auto& p : pts) points.push_back(point(p));
  return {{"type", type}, {"pose", identityPose()}, {"thickness", thickness}, {"scale_invariant", false},
          {"points", std::move(points)}, {"color", std::move(color)}, {"colors", json::array()}, {"indices", json::array()}};
}

std::string sceneMessage(const ReplayInput& in) {
  const PlanResult& r = *in.result;
  const double cell = std::max(in.grid.cellWidth, in.grid.cellHeight);
  json entities = json::array();
  for (const Polyline& o : r.overlays) {
    if (o.points.size() < 2) continue;
    const bool route = o.key == "route";
    const std::string id = route ? "route" : o.key + (o.rover >= 0 ? "_rover_" + std::to_string(o.rover) : std::string());
    json color = route ? rgba(1, 1, 1, 0.9) : o.rover >= 0 ? roverColor(o.rover) : rgba(0.8, 0.8, 0.8, 0.9);
    if (!route) color["a"] = 0.6;
    json meta = json::array({{{"key", "layer"}, {"value", route ? "route" : o.key}}});
    if (o.rover >= 0) meta.push_back({{"key", "rover"}, {"value", std::to_string(o.rover)}});
    entities.push_back(entity(id, json::array({line(0, o.points, route ? 0.6 : 0.25, color)}), json::array(), meta));
  }
  if (!r.targets.empty()) {
    json spheres = json::array();
    for (const RouteTarget& t : r.targets) {
      json c = t.status == TargetStatus::Reached ? rgba(0.18, 0.80, 0.44, 0.8) : rgba(0.95, 0.30, 0.24, 0.8);
      const double d = std::max(1.0, 4 * cell);
      spheres.push_back({{"pose", {{"position", point(t.position)}, {"orientation", identityPose()["orientation"]}}},
                         {"size", {{"x", d}, {"y", d}, {"z", d}}},
                         {"color", c}});
    }
    entities.push_back(entity("targets", json::array(), std::move(spheres), json::array({{{"key", "layer"}, {"value", "target"}}})));
  }
  for (std::size_t i = 0; i < in.zones.size(); ++i) {
    const maps::Zone& z = in.zones[i];
    json lines = json::array();
    for (const auto& ring : z.rings)
      if (ring.size() >= 3) lines.push_back(line(1, ring, 0.4, rgba(0.95, 0.15, 0.15, 0.9)));
    if (lines.empty()) continue;
    json meta = json::array({{{"key", "layer"}, {"value", "zone"}}});
    if (!z.name.empty()) meta.push_back({{"key", "name"}, {"value", z.name}});
    entities.push_back(entity("zone_" + std::to_string(i), std::move(lines), json::array(), std::move(meta)));
  }
  return json{{"deletions", json::array()}, {"entities", std::move(entities)}}.dump();
}

// ---- Terrain --------------------------------------------------------------------------------------

std::string terrainMessage(const terrain::Dem& dem, const Eigen::Vector2d& origin) {
  const GridGeometry& g = dem.geometry();
  const int f = terrainStride(g.rows, g.cols);
  const int rows = (g.rows + f - 1) / f, cols = (g.cols + f - 1) / f;
  // Grid data is y-major from the grid's corner at the pose (the local origin, the map's south-west
  // corner): data row 0 is the southernmost block row, i.e. the DEM's last rows.
  std::vector<unsigned char> bytes(static_cast<std::size_t>(rows) * cols * 4);
  for (int br = 0; br < rows; ++br) {
    for (int bc = 0; bc < cols; ++bc) {
      double sum = 0;
      int n = 0;
      for (int dr = 0; dr < f; ++dr) {
        const int row = g.rows - 1 - (br * f + dr);  // counted from the south edge
        if (row < 0) break;
        for (int dc = 0; dc < f && bc * f + dc < g.cols; ++dc) {
          const float z = dem.z(row, bc * f + dc);
          if (!std::isnan(z)) {
            sum += z;
            ++n;
          }
        }
      }
      const float v = n ? static_cast<float>(sum / n) : std::numeric_limits<float>::quiet_NaN();
      std::uint32_t bits;
      std::memcpy(&bits, &v, 4);
      unsigned char* out = &bytes[(static_cast<std::size_t>(br) * cols + bc) * 4];
      for (int b = 0; b < 4; ++b) out[b] = static_cast<unsigned char>(bits >> (8 * b));  // little-endian
    }
  }
  json m{{"timestamp", timeJson(0)},
         {"frame_id", "map"},
         {"pose", {{"position", {{"x", origin.x()}, {"y", origin.y()}, {"z", 0.0}}},
                   {"orientation", identityPose()["orientation"]}}},
         {"column_count", cols},
         {"cell_size", {{"x", g.cellWidth * f}, {"y", g.cellHeight * f}}},
         {"row_stride", cols * 4},
         {"cell_stride", 4},
         {"fields", json::array({{{"name", "elevation"}, {"offset", 0}, {"type", 7}}})}};  // 7 = FLOAT32
  std::string text = m.dump();
  text.pop_back();  // the data, appended without a copy of the whole tree: ,"data":"..."}
  text += ",\"data\":\"" + base64(bytes.data(), bytes.size()) + "\"}";
  return text;
}

// ---- Samples and incidents ------------------------------------------------------------------------

// A rover's samples on the mission clock when the planner has no clock: the path's points, one a
// second, with what the DEM says about them (a clock's samples are used where they are).
std::vector<TrackSample> pointSamples(const Track& t, const ReplayInput& in, std::size_t k) {
  std::vector<TrackSample> out;
  out.reserve(t.points.size());
  const double heading = k < in.startHeadings.size() ? in.startHeadings[k] : 0.0;
  std::vector<Eigen::Vector2d> onDem = t.points;  // the DEM may be a mission area's window
  for (auto& p : onDem) p -= in.demOrigin;
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    TrackSample s = groundSample(onDem, i, heading, in.dem);
    s.position = t.points[i];
    s.time = static_cast<double>(i);
    out.push_back(s);
  }
  return out;
}

// Energy used by `time` from the rover's cumulative series (linear between its points), NaN
// without one.
double energyAt(const Series* e, double time) {
  if (!e || e->x.empty() || !std::isfinite(time)) return std::numeric_limits<double>::quiet_NaN();
  auto it = std::upper_bound(e->x.begin(), e->x.end(), time);
  if (it == e->x.begin()) return e->y.front();
  if (it == e->x.end()) return e->y.back();
  const std::size_t j = static_cast<std::size_t>(it - e->x.begin());
  const double x0 = e->x[j - 1], x1 = e->x[j];
  const double a = x1 > x0 ? (time - x0) / (x1 - x0) : 1.0;
  return e->y[j - 1] + a * (e->y[j] - e->y[j - 1]);
}

void putField(std::string& s, const char* key, double v, int decimals) {
  if (!std::isfinite(v)) return;
  s += ",\"";
  s += key;
  s += "\":";
  putNumber(s, v, decimals);
}

int logLevel(IncidentKind k) {
  return k == IncidentKind::Collision ? 4 : 3;  // ERROR for a collision, WARNING for the rest
}

}  // namespace

std::vector<maps::Zone> zonesOf(const KeepOut& keepOut, const Eigen::Vector2d& by) {
  std::vector<maps::Zone> out;
  for (Polygon p : keepOut.zones) {
    for (auto& ring : p)
      for (auto& v : ring) v += by;
    out.push_back({std::move(p), ""});
  }
  return out;
}

int terrainStride(int rows, int cols) {
  int f = 1;
  auto cells = [&](int s) {
    return static_cast<std::int64_t>((rows + s - 1) / s) * ((cols + s - 1) / s);
  };
  while (cells(f) > kMaxTerrainCells) ++f;
  return f;
}

McapTotals writeReplayMcap(const ReplayInput& in, std::ostream& out) {
  if (!in.result) throw std::logic_error("writeReplayMcap: no result");
  const PlanResult& r = *in.result;
  McapWriter w(out);
  const auto jsonSchema = [&](const json& doc) { return w.addSchema(doc["title"].get<std::string>(), "jsonschema", doc.dump()); };
  const std::uint16_t gridS = jsonSchema(gridSchema()), sceneS = jsonSchema(sceneUpdateSchema()), logS = jsonSchema(logSchema()),
                      poseS = jsonSchema(poseInFrameSchema()), telemetryS = jsonSchema(telemetrySchema());
  const std::optional<maps::LonLatOfLocal> lonLat =
      in.dem ? maps::LonLatOfLocal::make(in.grid, in.geo) : std::optional<maps::LonLatOfLocal>{};
  const std::uint16_t fixS = lonLat ? jsonSchema(locationFixSchema()) : 0;

  const std::uint16_t terrainC = in.dem ? w.addChannel(gridS, "/map/terrain", "json") : 0;
  const std::uint16_t sceneC = w.addChannel(sceneS, "/map/scene", "json");
  const std::uint16_t logC = w.addChannel(logS, "/incidents", "json");
  struct Rover {
    std::uint16_t pose = 0, fix = 0, telemetry = 0;
    std::vector<TrackSample> own;               // coverage: built from the path
    const std::vector<TrackSample>* samples = nullptr;  // the track's own, or `own`
    const Series* energy = nullptr;
  };
  std::vector<Rover> rovers(r.tracks.size());
  for (std::size_t k = 0; k < r.tracks.size(); ++k) {
    const std::string name = "/rover_" + std::to_string(r.tracks[k].rover);
    rovers[k].pose = w.addChannel(poseS, name + "/pose", "json");
    if (lonLat) rovers[k].fix = w.addChannel(fixS, name + "/fix", "json");
    rovers[k].telemetry = w.addChannel(telemetryS, name + "/telemetry", "json");
    if (r.tracks[k].samples.empty()) rovers[k].own = pointSamples(r.tracks[k], in, k);
    rovers[k].samples = r.tracks[k].samples.empty() ? &rovers[k].own : &r.tracks[k].samples;
    const std::string key = "energy_j_rover_" + std::to_string(r.tracks[k].rover);
    for (const Series& s : r.series)
      if (s.key == key) rovers[k].energy = &s;
  }

  if (in.dem) w.write(terrainC, 0, 0, terrainMessage(*in.dem, in.demOrigin));
  w.write(sceneC, 0, 0, sceneMessage(in));

  // Everything timed, in time order (ties: incidents first, then rovers in order), so chunks
  // cover short spans and a player reads them in sequence.
  struct Event {
    std::uint64_t t;
    std::uint32_t rover;  // kIncident for an incident
    std::uint32_t index;
  };
  constexpr std::uint32_t kIncident = UINT32_MAX;
  std::vector<Event> events;
  for (std::size_t i = 0; i < r.incidents.size(); ++i) {
    const Incident& x = r.incidents[i];
    const double time = x.step >= 0 ? static_cast<double>(x.step) : x.time;
    events.push_back({toNs(time), kIncident, static_cast<std::uint32_t>(i)});
  }
  for (std::size_t k = 0; k < rovers.size(); ++k)
    for (std::size_t i = 0; i < rovers[k].samples->size(); ++i)
      events.push_back({toNs((*rovers[k].samples)[i].time), static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(i)});
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
    if (a.t != b.t) return a.t < b.t;
    return (a.rover == kIncident) > (b.rover == kIncident);
  });

  std::string m;
  for (const Event& e : events) {
    m.clear();
    if (e.rover == kIncident) {
      const Incident& x = r.incidents[e.index];
      std::string text = std::string(enumName(x.kind)) + " at (";
      putNumber(text, x.position.x(), 2);
      text += ", ";
      putNumber(text, x.position.y(), 2);
      text += ") m: " + x.note;
      json log{{"timestamp", timeJson(e.t)},
               {"level", logLevel(x.kind)},
               {"message", std::move(text)},
               {"name", "rover_" + std::to_string(x.rover)},
               {"file", ""},
               {"line", 0}};
      w.write(logC, e.t, e.t, log.dump(-1, ' ', false, json::error_handler_t::replace));
      continue;
    }
    const Rover& rv = rovers[e.rover];
    const TrackSample& s = (*rv.samples)[e.index];
    const int rover = r.tracks[e.rover].rover;
    const double yaw = std::isfinite(s.heading) ? s.heading : 0.0;
    m += "{\"timestamp\":";
    putTime(m, e.t);
    m += ",\"frame_id\":\"map\",\"pose\":{\"position\":{\"x\":";
    putNumber(m, s.position.x(), 4);
    m += ",\"y\":";
    putNumber(m, s.position.y(), 4);
    m += ",\"z\":0},\"orientation\":{\"x\":0,\"y\":0,\"z\":";
    putNumber(m, std::sin(yaw / 2), 7);
    m += ",\"w\":";
    putNumber(m, std::cos(yaw / 2), 7);
    m += "}}}";
    w.write(rv.pose, e.t, e.t, m);

    if (lonLat) {
      if (const auto ll = (*lonLat)(s.position)) {
        m.clear();
        m += "{\"timestamp\":";
        putTime(m, e.t);
        m += ",\"frame_id\":\"rover_" + std::to_string(rover) + "\",\"latitude\":";
        putNumber(m, ll->y(), 9);
        m += ",\"longitude\":";
        putNumber(m, ll->x(), 9);
        m += ",\"altitude\":";
        putNumber(m, std::isfinite(s.elevation) ? s.elevation : 0.0, 3);
        m += ",\"position_covariance\":[0,0,0,0,0,0,0,0,0],\"position_covariance_type\":0}";
        w.write(rv.fix, e.t, e.t, m);
      }
    }

    m.clear();
    m += "{\"timestamp\":";
    putTime(m, e.t);
    m += ",\"rover\":" + std::to_string(rover);
    putField(m, "pitch_deg", s.pitch * kDeg, 3);
    putField(m, "roll_deg", s.roll * kDeg, 3);
    putField(m, "heading_deg", s.heading * kDeg, 2);
    putField(m, "speed_m_s", s.speed, 4);
    putField(m, "energy_j", energyAt(rv.energy, s.time), 2);
    putField(m, "elevation_m", s.elevation, 3);
    m += '}';
    w.write(rv.telemetry, e.t, e.t, m);
  }
  return w.finish();
}

namespace {

// An output buffer over a file descriptor that keeps the errno of a failed write: a full disk must
// be told apart from other failures, and std::ofstream does not say why it failed.
class FdBuffer : public std::streambuf {
 public:
  explicit FdBuffer(int fd) : fd_(fd), buf_(1 << 20) { setp(buf_.data(), buf_.data() + buf_.size()); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (p < pptr()) {
      const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        error_ = n < 0 ? errno : EIO;
        return false;
      }
      p += n;
    }
    setp(buf_.data(), buf_.data() + buf_.size());
    return true;
  }
  int fd_;
  std::vector<char> buf_;
  int error_ = 0;
};

}  // namespace

McapTotals writeReplayMcapFile(const ReplayInput& in, const std::string& path) {
  // A full disk is the server's StorageFull like every other result file's (507, and "insufficient
  // storage" in a mission's message).
  auto failed = [](int err, const char* what) {
    if (store::isStorageFullErrno(err)) throw store::StorageFull("cannot store the MCAP replay");
    throw std::runtime_error(what);
  };
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) failed(errno, "the MCAP replay file cannot be created");
  FdBuffer buffer(fd);
  std::ostream out(&buffer);
  McapTotals t;
  bool ok = true;
  try {
    t = writeReplayMcap(in, out);
    ok = static_cast<bool>(out.flush());
  } catch (const std::runtime_error&) {
    ok = false;
  }
  const int closed = ::close(fd);
  if (ok && closed != 0) ok = false;
  if (!ok) failed(buffer.error() ? buffer.error() : errno, "the MCAP replay file could not be written");
  return t;
}

}  // namespace rover::exports
