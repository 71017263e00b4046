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

std::string tracksToGeoJson(const std::vector<Track>& tracks, const GridGeometry& g,
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

  // Property fields: "rover", then every metric key in order of first appearance (a track
  // without some metric leaves it null).
  std::vector<std::string> metricKeys;
  for (const Track& t : tracks)
    for (const Metric& m : t.metrics) {
      const std::string name = fieldNameFor(m.key);
      bool known = false;
      for (const auto& k : metricKeys) known = known || k == name;
      if (!known) metricKeys.push_back(name);
    }

  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GeoJSON");
  if (driver == nullptr) throw std::runtime_error("GeoJSON export: GDAL has no GeoJSON driver");

  const std::string path = uniqueVsimemPath();
  {
    DatasetPtr ds(driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!ds) throwGdal("cannot create " + path);

    char** layerOptions = CSLSetNameValue(nullptr, "RFC7946", "NO");
    OGRLayer* layer =
        ds->CreateLayer("tracks", haveSrs ? &srs : nullptr, wkbUnknown, layerOptions);
    CSLDestroy(layerOptions);
    if (layer == nullptr) throwGdal("cannot create the layer");

    OGRFieldDefn roverField("rover", OFTInteger);
    if (layer->CreateField(&roverField) != OGRERR_NONE) throwGdal("cannot create field rover");
    // Localisation error (coverage): each rover's true track, then its believed one.
    bool believed = false;
    for (const Track& t : tracks) believed = believed || !t.believed.empty();
    if (believed) {
      OGRFieldDefn trackField("track", OFTString);
      if (layer->CreateField(&trackField) != OGRERR_NONE) throwGdal("cannot create field track");
    }
    for (const auto& key : metricKeys) {
      OGRFieldDefn field(key.c_str(), OFTReal);
      if (layer->CreateField(&field) != OGRERR_NONE) throwGdal("cannot create field " + key);
    }

    // One feature: its geometry from `points` (a LineString needs two points: a one-point track
    // is a Point, an empty one has no geometry).
    auto writeFeature = [&](OGRFeature& feature, const Track& t,
                            const std::vector<Eigen::Vector2d>& points) {
      std::vector<Eigen::Vector2d> crs;
      crs.reserve(points.size());
      for (const auto& p : points) {
        const Eigen::Vector2d c = localToCrs(g, geo, p);
        if (!std::isfinite(c.x()) || !std::isfinite(c.y()))
          throw Error(ErrorCode::InvalidInput, "tracks",
                      "track of rover " + std::to_string(t.rover) + " has a non-finite point");
        crs.push_back(c);
      }
      if (crs.size() >= 2) {
        OGRLineString line;
        line.setNumPoints(static_cast<int>(crs.size()));
        for (std::size_t i = 0; i < crs.size(); ++i)
          line.setPoint(static_cast<int>(i), crs[i].x(), crs[i].y());
        feature.SetGeometry(&line);
      } else if (crs.size() == 1) {
        OGRPoint point(crs[0].x(), crs[0].y());
        feature.SetGeometry(&point);
      }
      if (layer->CreateFeature(&feature) != OGRERR_NONE)
        throwGdal("cannot write the track of rover " + std::to_string(t.rover));
    };

    for (const Track& t : tracks) {
      OGRFeature feature(layer->GetLayerDefn());
      feature.SetField("rover", t.rover);
      if (believed) feature.SetField("track", "true");
      for (const Metric& m : t.metrics) {
        const std::string name = fieldNameFor(m.key);
        // Non-finite values would make invalid JSON: store them as null.
        if (std::isfinite(m.value))
          feature.SetField(name.c_str(), m.value);
        else
          feature.SetFieldNull(feature.GetFieldIndex(name.c_str()));
      }
      writeFeature(feature, t, t.points);
      if (!t.believed.empty()) {
        OGRFeature b(layer->GetLayerDefn());
        b.SetField("rover", t.rover);
        b.SetField("track", "believed");
        writeFeature(b, t, t.believed);
      }
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

}  // namespace rover::maps
