#include "maps/geojson.hpp"

#include <cpl_conv.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::maps {

namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

std::string uniqueVsimemPath() {
  static std::atomic<unsigned long long> counter{0};
  return "/vsimem/rover_tracks_" + std::to_string(counter.fetch_add(1)) + ".geojson";
}

std::string jsonEscape(const std::string& s) {
  std::string out;
  out.reserve(s.size() + 16);
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out;
}

// The field name a metric is stored under: the metric's key, unless it would clash with "rover".
std::string fieldNameFor(const std::string& key) {
  if (key == "rover") return "rover_metric";
  if (key.empty()) return "metric";
  return key;
}

[[noreturn]] void throwGdal(const std::string& what) {
  throw std::runtime_error("GeoJSON export: " + what + ": " + CPLGetLastErrorMsg());
}

}  // namespace

namespace {

// One feature before it is written: its properties in order and its geometry in the local frame.
using Value = std::variant<std::monostate, std::int64_t, double, std::string>;
struct PendingFeature {
  std::vector<std::pair<std::string, Value>> props;
  enum class Shape { None, Point, Line, Polygon } shape = Shape::None;
  std::vector<std::vector<Eigen::Vector2d>> rings;  // Point/Line: rings[0]; Polygon: outer, holes
};

double pathLength(const std::vector<Eigen::Vector2d>& p) {
  double d = 0;
  for (std::size_t i = 1; i < p.size(); ++i) d += (p[i] - p[i - 1]).norm();
  return d;
}

// A path's geometry: a LineString needs two points, a one-point path is a Point, an empty one
// has no geometry.
void setPath(PendingFeature& f, const std::vector<Eigen::Vector2d>& points) {
  f.shape = points.size() >= 2  ? PendingFeature::Shape::Line
            : points.size() == 1 ? PendingFeature::Shape::Point
                                 : PendingFeature::Shape::None;
  f.rings = {points};
}

std::vector<PendingFeature> missionFeatures(const PlanResult& v, const std::vector<Zone>& zones) {
  std::vector<PendingFeature> out;
  bool believed = false;
  for (const Track& t : v.tracks) believed = believed || !t.believed.empty();
  for (const Track& t : v.tracks) {
    PendingFeature f;
    f.props = {{"layer", std::string("track")}, {"rover", std::int64_t{t.rover}}};
    if (believed) f.props.emplace_back("track", std::string("true"));
    f.props.emplace_back("length_m", pathLength(t.points));
    // Duration only for a planner with a clock (team); coverage counts moves (its metrics).
    if (!t.samples.empty() && std::isfinite(t.samples.back().time) && std::isfinite(t.samples.front().time))
      f.props.emplace_back("duration_s", t.samples.back().time - t.samples.front().time);
    for (const Metric& m : t.metrics)
      f.props.emplace_back(fieldNameFor(m.key), std::isfinite(m.value) ? Value(m.value) : Value());
    setPath(f, t.points);
    out.push_back(std::move(f));
    if (!t.believed.empty()) {
      PendingFeature b;
      b.props = {{"layer", std::string("track")}, {"rover", std::int64_t{t.rover}},
                 {"track", std::string("believed")}, {"length_m", pathLength(t.believed)}};
      setPath(b, t.believed);
      out.push_back(std::move(b));
    }
  }
  for (const Polyline& o : v.overlays) {
    if (o.key != "route") continue;
    PendingFeature f;
    // The team route: the start centre, then the targets in visiting order.
    f.props = {{"layer", std::string("route")},
               {"targets", static_cast<std::int64_t>(o.points.empty() ? 0 : o.points.size() - 1)},
               {"length_m", pathLength(o.points)}};
    setPath(f, o.points);
    out.push_back(std::move(f));
  }
  for (const RouteTarget& t : v.targets) {
    PendingFeature f;
    f.props = {{"layer", std::string("target")},   {"target", std::int64_t{t.index}},
               {"status", std::string(enumName(t.status))}, {"legs_reached", std::int64_t{t.reached}},
               {"legs_short", std::int64_t{t.shortLegs}}, {"legs_skipped", std::int64_t{t.skipped}},
               {"legs_no_slot", std::int64_t{t.noSlot}}};
    f.shape = PendingFeature::Shape::Point;
    f.rings = {{t.position}};
    out.push_back(std::move(f));
  }
  for (std::size_t i = 0; i < zones.size(); ++i) {
    const Zone& z = zones[i];
    if (z.rings.empty() || z.rings[0].size() < 3) continue;
    PendingFeature f;
    f.props = {{"layer", std::string("zone")}, {"zone", static_cast<std::int64_t>(i)}};
    if (!z.name.empty()) f.props.emplace_back("name", z.name);
    f.shape = PendingFeature::Shape::Polygon;
    f.rings = z.rings;
    out.push_back(std::move(f));
  }
  for (const Incident& inc : v.incidents) {
    PendingFeature f;
    f.props = {{"layer", std::string("incident")}, {"rover", std::int64_t{inc.rover}}, {"kind", std::string(enumName(inc.kind))}};
    if (inc.step >= 0)
      f.props.emplace_back("step", std::int64_t{inc.step});  // a planner without a clock
    else
      f.props.emplace_back("time_s", inc.time);
    if (inc.other >= 0) f.props.emplace_back("other", std::int64_t{inc.other});
    f.props.emplace_back("note", inc.note);
    f.shape = PendingFeature::Shape::Point;
    f.rings = {{inc.position}};
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace

std::string missionToGeoJson(const PlanResult& v, const std::vector<Zone>& zones, const GridGeometry& g,
                             const GeoReference& geo) {
  ensureGdal();

  // The CRS. GDAL 3.6's GeoJSON writer only writes a "crs" member for a CRS with an authority
  // code (as "urn:ogc:def:crs:AUTH::CODE", e.g. EPSG::32633 or IAU_2015::49910) and silently
  // drops any other, and a reader then assumes WGS 84 — wrong for a Mars or Moon map. For those
  // we add the member ourselves as a named CRS whose name is the WKT2 text: GDAL's reader passes
  // the name to OGRSpatialReference::SetFromUserInput, which takes WKT, so ogrinfo, QGIS and our
  // own loader read the map's CRS back exactly. RFC7946=NO (the default) is required: RFC 7946
  // output would be reprojected to WGS 84 longitude/latitude, meaningless off Earth.
  OGRSpatialReference srs;
  bool haveSrs = false;
  bool embedWkt = false;
  if (!geo.crsWkt.empty()) {
    if (srs.SetFromUserInput(geo.crsWkt.c_str(),
                             OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) !=
        OGRERR_NONE)
      throw Error(ErrorCode::InvalidInput, "crs", "the map's CRS could not be parsed");
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // geotransform order: x, y
    haveSrs = true;
    embedWkt = srs.GetAuthorityName(nullptr) == nullptr || srs.GetAuthorityCode(nullptr) == nullptr;
  }

  const std::vector<PendingFeature> features = missionFeatures(v, zones);
  // Fields in order of first appearance, typed by their first non-null value (a feature
  // without some field leaves it null).
  std::vector<std::pair<std::string, OGRFieldType>> fields;
  for (const auto& f : features)
    for (const auto& [name, value] : f.props) {
      bool known = false;
      for (auto& [n, type] : fields)
        if (n == name) {
          known = true;
          if (type == OFTInteger64 && std::holds_alternative<double>(value)) type = OFTReal;
        }
      if (known) continue;
      const OGRFieldType type = std::holds_alternative<std::int64_t>(value) ? OFTInteger64
                                : std::holds_alternative<std::string>(value) ? OFTString
                                                                             : OFTReal;
      fields.emplace_back(name, type);
    }

  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GeoJSON");
  if (driver == nullptr) throw std::runtime_error("GeoJSON export: GDAL has no GeoJSON driver");

  const std::string path = uniqueVsimemPath();
  {
    DatasetPtr ds(driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!ds) throwGdal("cannot create " + path);

    char** layerOptions = CSLSetNameValue(nullptr, "RFC7946", "NO");
    OGRLayer* layer = ds->CreateLayer("mission", haveSrs ? &srs : nullptr, wkbUnknown, layerOptions);
    CSLDestroy(layerOptions);
    if (layer == nullptr) throwGdal("cannot create the layer");
    for (const auto& [name, type] : fields) {
      // "rover" stays a 32-bit integer (as before: readers type it Integer).
      OGRFieldDefn field(name.c_str(), type == OFTInteger64 ? OFTInteger : type);
      if (layer->CreateField(&field) != OGRERR_NONE) throwGdal("cannot create field " + name);
    }

    for (const PendingFeature& pf : features) {
      OGRFeature feature(layer->GetLayerDefn());
      for (const auto& [name, value] : pf.props) {
        const int i = feature.GetFieldIndex(name.c_str());
        if (const auto* n = std::get_if<std::int64_t>(&value))
          feature.SetField(i, static_cast<GIntBig>(*n));
        else if (const auto* d = std::get_if<double>(&value))
          feature.SetField(i, *d);
        else if (const auto* s = std::get_if<std::string>(&value))
          feature.SetField(i, s->c_str());
        else
          feature.SetFieldNull(i);  // non-finite values would make invalid JSON
      }
      std::vector<std::vector<Eigen::Vector2d>> crs;
      for (const auto& ring : pf.rings) {
        auto& out = crs.emplace_back();
        for (const auto& p : ring) {
          const Eigen::Vector2d c = localToCrs(g, geo, p);
          if (!std::isfinite(c.x()) || !std::isfinite(c.y()))
            throw Error(ErrorCode::InvalidInput, "tracks", "a feature has a non-finite point");
          out.push_back(c);
        }
      }
      switch (pf.shape) {
        case PendingFeature::Shape::Point: {
          OGRPoint point(crs[0][0].x(), crs[0][0].y());
          feature.SetGeometry(&point);
          break;
        }
        case PendingFeature::Shape::Line: {
          OGRLineString line;
          line.setNumPoints(static_cast<int>(crs[0].size()));
          for (std::size_t i = 0; i < crs[0].size(); ++i)
            line.setPoint(static_cast<int>(i), crs[0][i].x(), crs[0][i].y());
          feature.SetGeometry(&line);
          break;
        }
        case PendingFeature::Shape::Polygon: {
          OGRPolygon polygon;
          for (const auto& ring : crs) {
            OGRLinearRing r;
            for (const auto& p : ring) r.addPoint(p.x(), p.y());
            r.closeRings();
            polygon.addRing(&r);
          }
          feature.SetGeometry(&polygon);
          break;
        }
        case PendingFeature::Shape::None: break;
      }
      if (layer->CreateFeature(&feature) != OGRERR_NONE) throwGdal("cannot write a feature");
    }
  }  // closing the dataset flushes the file

  vsi_l_offset length = 0;
  GByte* buffer = VSIGetMemFileBuffer(path.c_str(), &length, FALSE);
  if (buffer == nullptr) {
    VSIUnlink(path.c_str());
    throw std::runtime_error("GeoJSON export: nothing was written to " + path);
  }
  std::string json(reinterpret_cast<const char*>(buffer), static_cast<std::size_t>(length));
  VSIUnlink(path.c_str());

  if (embedWkt) {
    const char* const wktOptions[] = {"FORMAT=WKT2_2019", "MULTILINE=NO", nullptr};
    char* wktText = nullptr;
    std::string wkt;
    if (srs.exportToWkt(&wktText, wktOptions) == OGRERR_NONE && wktText != nullptr) wkt = wktText;
    CPLFree(wktText);
    const std::string anchor = "\n\"features\": [";
    const auto at = json.find(anchor);
    if (wkt.empty() || at == std::string::npos)
      throw std::runtime_error("GeoJSON export: cannot add the CRS to the GeoJSON document");
    json.insert(at + 1, "\"crs\": { \"type\": \"name\", \"properties\": { \"name\": \"" +
                            jsonEscape(wkt) + "\" } },\n");
  }
  return json;
}

std::string tracksToGeoJson(const std::vector<Track>& tracks, const GridGeometry& g,
                            const GeoReference& geo) {
  PlanResult r;
  r.tracks = tracks;
  return missionToGeoJson(r, {}, g, geo);
}

}  // namespace rover::maps
