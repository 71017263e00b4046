#include "maps/result_csv.hpp"

#include <ogr_spatialref.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string_view>

#include "core/planning/ground_sample.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::maps {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// `v` with `decimals` decimals, or nothing when unknown (an empty CSV cell).
void put(std::string& out, double v, int decimals) {
  out += ',';
  if (!std::isfinite(v)) return;
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  // A tiny negative value rounds to "-0.00": written as 0.
  const bool zero = std::string_view(buf).find_first_not_of("-0.") == std::string_view::npos;
  out += zero && buf[0] == '-' ? buf + 1 : buf;
}

}  // namespace

std::pair<std::string, std::string> crsColumnNames(const GeoReference& geo) {
  if (geo.crsWkt.empty()) return {"crs_x", "crs_y"};
  ensureGdal();
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(geo.crsWkt.c_str(), OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) !=
      OGRERR_NONE)
    return {"crs_x", "crs_y"};
  if (srs.IsGeographic()) return {"lon_deg", "lat_deg"};
  if (srs.IsProjected() && std::abs(srs.GetLinearUnits() - 1.0) < 1e-12) return {"easting_m", "northing_m"};
  return {"crs_x", "crs_y"};
}

std::string resultCsv(const std::vector<Track>& tracks, const GridGeometry& g, const GeoReference& geo,
                      const terrain::Dem* dem, const std::vector<double>& startHeadings,
                      const Eigen::Vector2d& demOrigin) {
  bool clock = false, believed = false;
  for (const auto& t : tracks) {
    clock = clock || !t.samples.empty();
    believed = believed || !t.believed.empty();
  }
  const auto [cx, cy] = crsColumnNames(geo);
  // Degrees need 9 decimals for millimetres; projected metres 3.
  const int crsDecimals = cx == "lon_deg" ? 9 : 3;
  std::string out = "rover," + std::string(clock ? "time_s" : "move") + ",x_m,y_m," + cx + "," + cy +
                    ",heading_deg,roll_deg,pitch_deg," + (clock ? "speed_m_s," : "") + "elevation_m" +
                    (believed ? ",believed_x_m,believed_y_m" : "") + "\n";
  auto row = [&](int rover, double index, int indexDecimals, const TrackSample& s, const Eigen::Vector2d* b) {
    out += std::to_string(rover);
    put(out, index, indexDecimals);
    put(out, s.position.x(), 3);
    put(out, s.position.y(), 3);
    const Eigen::Vector2d c = localToCrs(g, geo, s.position);
    put(out, c.x(), crsDecimals);
    put(out, c.y(), crsDecimals);
    put(out, s.heading * kDeg, 2);
    put(out, s.roll * kDeg, 2);
    put(out, s.pitch * kDeg, 2);
    if (clock) put(out, s.speed, 3);
    put(out, s.elevation, 3);
    if (believed) {
      if (b != nullptr) {
        put(out, b->x(), 3);
        put(out, b->y(), 3);
      } else {
        out += ",,";
      }
    }
    out += '\n';
  };
  for (const Track& t : tracks) {
    if (!t.samples.empty()) {
      for (const TrackSample& s : t.samples) row(t.rover, s.time, 1, s, nullptr);
      continue;
    }
    const double start = t.rover >= 0 && static_cast<std::size_t>(t.rover) < startHeadings.size()
                             ? startHeadings[static_cast<std::size_t>(t.rover)]
                             : 0.0;
    // The DEM may be a mission area's window: its heights are read in the window's frame.
    std::vector<Eigen::Vector2d> onDem = t.points;
    for (auto& p : onDem) p -= demOrigin;
    for (std::size_t i = 0; i < t.points.size(); ++i) {
      TrackSample s = groundSample(onDem, i, start, dem);
      s.position = t.points[i];
      row(t.rover, static_cast<double>(i), 0, s, i < t.believed.size() ? &t.believed[i] : nullptr);
    }
  }
  return out;
}

}  // namespace rover::maps
