#include "maps/mission_map.hpp"

#include <cpl_conv.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/common/error.hpp"
#include "core/terrain/layers.hpp"
#include "maps/painter.hpp"
#include "maps/gdal_env.hpp"

namespace rover::maps {

namespace {

// The page's rover colours (web/js/util.js ROVER_COLOURS), so the picture matches the screen.
constexpr Rgba kRover[] = {{255, 79, 154}, {58, 214, 255}, {255, 210, 63}, {157, 255, 92},
                             {192, 139, 255}, {255, 138, 61}, {255, 255, 255}, {92, 255, 200}};
constexpr Rgba kPaper{255, 255, 255};
constexpr Rgba kVisited{40, 120, 255, 90};
constexpr Rgba kRoute{255, 255, 255, 230};
constexpr Rgba kZone{230, 30, 30, 70};
constexpr Rgba kZoneEdge{230, 30, 30, 255};
constexpr Rgba kIncident{255, 40, 40};

Rgba statusColour(TargetStatus s) {
  switch (s) {
    case TargetStatus::Reached: return {40, 200, 90};
    case TargetStatus::Short: return {255, 170, 0};
    case TargetStatus::Skipped: return {230, 40, 40};
    case TargetStatus::Unreachable: break;
  }
  return {120, 120, 120};
}

// Even-odd fill of a polygon's rings (pixel coordinates), scanline by scanline.
void fillPolygon(Painter& p, const std::vector<std::vector<Eigen::Vector2d>>& rings, int height, Rgba c) {
  for (int y = 0; y < height; ++y) {
    const double sy = y + 0.5;
    std::vector<double> xs;
    for (const auto& ring : rings)
      for (std::size_t i = 0; i < ring.size(); ++i) {
        const auto& a = ring[i];
        const auto& b = ring[(i + 1) % ring.size()];
        if ((a.y() <= sy) != (b.y() <= sy)) xs.push_back(a.x() + (sy - a.y()) / (b.y() - a.y()) * (b.x() - a.x()));
      }
    std::sort(xs.begin(), xs.end());
    for (std::size_t i = 0; i + 1 < xs.size(); i += 2)
      for (int x = static_cast<int>(std::ceil(xs[i] - 0.5)); x <= static_cast<int>(std::floor(xs[i + 1] - 0.5)); ++x)
        p.blend(x, y, c);
  }
}

// 1, 2 or 5 × 10^k metres: the largest not over `target`.
double niceLength(double target) {
  const double e = std::pow(10.0, std::floor(std::log10(target)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * e <= target) return m * e;
  return e;
}

std::string metres(double m) {
  char buf[32];
  if (m >= 1000)
    std::snprintf(buf, sizeof buf, "%g km", m / 1000);
  else
    std::snprintf(buf, sizeof buf, "%g m", m);
  return buf;
}

// `src` enlarged k× (nearest) and blended onto `dst` with its top-left at (x0, y0).
void enlargeInto(Image& dst, const Image& src, int x0, int y0, int k) {
  Painter p(dst);
  for (int y = 0; y < src.height * k; ++y)
    for (int x = 0; x < src.width * k; ++x) {
      const std::uint8_t* s = &src.rgba[(std::size_t(y / k) * src.width + x / k) * 4];
      if (s[3] > 0) p.blend(x0 + x, y0 + y, {s[0], s[1], s[2], s[3]});
    }
}

struct LegendItem {
  enum class Mark { Box, Line, Dot, Cross } mark;
  Rgba colour;
  std::string label;
};

}  // namespace

MissionMap renderMissionMap(const MissionMapInput& in) {
  if (in.dem == nullptr || in.dem->z.empty())
    throw Error(ErrorCode::InvalidInput, "dem", "the mission map needs the map's DEM");
  const GridGeometry& g = in.dem->geometry();
  if (std::max(g.rows, g.cols) > kMissionMapMaxSide)
    throw Error(ErrorCode::InvalidInput, "dem", "the DEM is larger than the mission map's cap");
  const Raster<float> shade = terrain::hillshade(*in.dem);
  RenderInput ri;
  ri.dem = in.dem;
  ri.hillshade = &shade;
  MissionMap out;
  // Legends and the scale bar are drawn at 1/k and enlarged k×: legible on a 4096 px picture.
  const int k = std::max(1, static_cast<int>(std::lround(std::max(g.rows, g.cols) / 1000.0)));
  Image base = renderLayer(RenderLayer::Elevation, ri, {0, true, k});  // map, then its ramp legend
  out.mapWidth = g.cols;
  out.mapHeight = g.rows;
  const double widthM = g.widthMetres(), heightM = g.heightMetres();
  auto px = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(p.x() / widthM * g.cols, (1.0 - p.y() / heightM) * g.rows);
  };
  Painter paint(base);
  const double scale = std::max(1.0, std::max(g.rows, g.cols) / 600.0);  // line widths grow with the map

  // Coverage: visited cells tinted, so the tracks stay readable on top.
  const GridGeometry& cg = in.coverageGrid;
  if (!in.coverageStates.empty() && in.coverageStates.size() == std::size_t(cg.rows) * cg.cols)
    for (int r = 0; r < cg.rows; ++r)
      for (int c = 0; c < cg.cols; ++c) {
        if (in.coverageStates[std::size_t(r) * cg.cols + c] != 3) continue;
        const Eigen::Vector2d a = px({c * cg.cellWidth, (cg.rows - r) * cg.cellHeight});
        const Eigen::Vector2d b = px({(c + 1) * cg.cellWidth, (cg.rows - r - 1) * cg.cellHeight});
        const int x0 = static_cast<int>(std::lround(a.x())), y0 = static_cast<int>(std::lround(a.y()));
        paint.rect(x0, y0, std::max(1, static_cast<int>(std::lround(b.x())) - x0),
                   std::max(1, static_cast<int>(std::lround(b.y())) - y0), kVisited);
      }
  for (const Zone& z : in.zones) {
    std::vector<std::vector<Eigen::Vector2d>> rings;
    for (const auto& ring : z.rings) {
      auto& r = rings.emplace_back();
      for (const auto& p : ring) r.push_back(px(p));
    }
    fillPolygon(paint, rings, g.rows, kZone);
    for (const auto& r : rings)
      for (std::size_t i = 0; i < r.size(); ++i) {
        const auto& a = r[i];
        const auto& b = r[(i + 1) % r.size()];
        paint.line(a.x(), a.y(), b.x(), b.y(), 1.5 * scale, kZoneEdge);
      }
  }
  for (std::size_t i = 1; i < in.route.size(); ++i) {
    const auto a = px(in.route[i - 1]), b = px(in.route[i]);
    paint.line(a.x(), a.y(), b.x(), b.y(), 1.0 * scale, kRoute);
  }
  for (const Track& t : in.tracks) {
    const Rgba c = kRover[static_cast<std::size_t>(std::max(0, t.rover)) % std::size(kRover)];
    for (std::size_t i = 1; i < t.points.size(); ++i) {
      const auto a = px(t.points[i - 1]), b = px(t.points[i]);
      paint.line(a.x(), a.y(), b.x(), b.y(), 1.5 * scale, c);
    }
    if (!t.points.empty()) {  // the start: a ringed dot
      const auto s = px(t.points.front());
      paint.disc(s.x(), s.y(), 4 * scale, kInk);
      paint.disc(s.x(), s.y(), 3 * scale, c);
    }
  }
  for (const RouteTarget& t : in.targets) {
    const auto p = px(t.position);
    paint.disc(p.x(), p.y(), 4.5 * scale, kInk);
    paint.disc(p.x(), p.y(), 3.5 * scale, statusColour(t.status));
  }
  for (const Incident& inc : in.incidents) {
    const auto p = px(inc.position);
    const double r = 3 * scale;
    paint.line(p.x() - r, p.y() - r, p.x() + r, p.y() + r, 1.2 * scale, kIncident);
    paint.line(p.x() - r, p.y() + r, p.x() + r, p.y() - r, 1.2 * scale, kIncident);
  }

  // Scale bar, bottom-left of the map: about a fifth of its width, on a white box.
  {
    const double len = niceLength(widthM / 5);
    const int barPx = std::max(1, static_cast<int>(std::lround(len / widthM * g.cols / k)));
    const std::string label = metres(len);
    Image bar;
    bar.width = std::max(barPx, font::textWidth(label)) + 8;
    bar.height = 22;
    bar.rgba.assign(std::size_t(bar.width) * bar.height * 4, 0);
    Painter bp(bar);
    bp.rect(0, 0, bar.width, bar.height, {255, 255, 255, 200});
    bp.rect(4, 13, barPx, 4, kInk);
    bp.rect(4, 10, 1, 7, kInk);
    bp.rect(4 + barPx - 1, 10, 1, 7, kInk);
    bp.text(label, 4, 2);
    const int x0 = 6 * k, y0 = g.rows - (bar.height + 6) * k;
    if (y0 > 0 && x0 + bar.width * k < g.cols) enlargeInto(base, bar, x0, y0, k);
  }

  // Legend of what is drawn, below the elevation ramp.
  std::vector<LegendItem> items;
  for (const Track& t : in.tracks) {
    // People count rovers from 1, as the page does (issue 27); the data files keep the ids.
    const std::string name = "rover " + std::to_string(t.rover + 1);
    if (t.rover >= 0 && (items.empty() || items.back().label != name))
      items.push_back({LegendItem::Mark::Line, kRover[static_cast<std::size_t>(t.rover) % std::size(kRover)], name});
  }
  if (!in.coverageStates.empty()) items.push_back({LegendItem::Mark::Box, kVisited, "covered cell"});
  if (in.route.size() > 1) items.push_back({LegendItem::Mark::Line, {140, 140, 140}, "route"});
  for (const auto& [s, name] : EnumNames<TargetStatus>::table) {
    bool any = false;
    for (const auto& t : in.targets) any = any || t.status == s;
    if (any) items.push_back({LegendItem::Mark::Dot, statusColour(s), "target " + std::string(name)});
  }
  if (!in.zones.empty()) items.push_back({LegendItem::Mark::Box, kZoneEdge, "keep-out zone"});
  if (!in.incidents.empty()) items.push_back({LegendItem::Mark::Cross, kIncident, "incident"});
  const int width = base.width, stripWidth = width / k;
  int x = 3, y = 14;
  std::vector<std::pair<int, int>> pos;
  for (const auto& it : items) {
    const int w = 14 + font::textWidth(it.label);
    if (x > 3 && x + w > stripWidth - 3) {
      x = 3;
      y += 11;
    }
    pos.emplace_back(x, y);
    x += w + 10;
  }
  Image strip;
  strip.width = stripWidth;
  strip.height = y + 12;
  strip.rgba.assign(std::size_t(strip.width) * strip.height * 4, 0);
  Painter lp(strip);
  lp.rect(0, 0, strip.width, strip.height, kPaper);
  lp.text(in.title.empty() ? std::string("mission") : in.title, 3, 3);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto [ix, iy] = pos[i];
    const int cy = iy + 3;
    switch (items[i].mark) {
      case LegendItem::Mark::Box: lp.rect(ix, cy - 3, 10, 7, items[i].colour); break;
      case LegendItem::Mark::Line: lp.rect(ix, cy - 1, 10, 3, items[i].colour); break;
      case LegendItem::Mark::Dot:
        lp.disc(ix + 5, cy + 0.5, 4, kInk);
        lp.disc(ix + 5, cy + 0.5, 3, items[i].colour);
        break;
      case LegendItem::Mark::Cross:
        lp.line(ix + 2, cy - 3, ix + 8, cy + 3, 1.2, items[i].colour);
        lp.line(ix + 2, cy + 3, ix + 8, cy - 3, 1.2, items[i].colour);
        break;
    }
    lp.text(items[i].label, ix + 14, iy);
  }
  out.image.width = width;
  out.image.height = base.height + strip.height * k;
  out.image.rgba = std::move(base.rgba);
  out.image.rgba.resize(std::size_t(out.image.width) * out.image.height * 4, 0);
  // The strip's background is opaque: fill the k leftover columns too.
  Painter(out.image).rect(0, base.height, width, strip.height * k, kPaper);
  enlargeInto(out.image, strip, 0, base.height, k);
  return out;
}

std::vector<std::uint8_t> encodeMissionMapGeoTiff(const MissionMap& m, const GridGeometry& mapGrid,
                                                  const GeoReference& geo) {
  ensureGdal();
  GDALDriverH gtiff = GDALGetDriverByName("GTiff");
  if (gtiff == nullptr) throw std::runtime_error("GeoTIFF export: GDAL lacks the GTiff driver");
  static std::atomic<unsigned long long> counter{0};
  const std::string path = "/vsimem/rover_mission_map_" + std::to_string(counter.fetch_add(1)) + ".tif";
  const char* options[] = {"COMPRESS=DEFLATE", "PHOTOMETRIC=RGB", "ALPHA=YES", nullptr};
  GDALDatasetH ds = GDALCreate(gtiff, path.c_str(), m.mapWidth, m.mapHeight, 4, GDT_Byte,
                               const_cast<char**>(options));
  if (ds == nullptr) throw std::runtime_error(std::string("GeoTIFF export: ") + CPLGetLastErrorMsg());
  // The map part: rows 0..mapHeight, columns 0..mapWidth of the picture (pixel-interleaved).
  auto* data = const_cast<std::uint8_t*>(m.image.rgba.data());
  CPLErr err = GDALDatasetRasterIO(ds, GF_Write, 0, 0, m.mapWidth, m.mapHeight, data, m.mapWidth,
                                   m.mapHeight, GDT_Byte, 4, nullptr, 4, 4 * m.image.width, 1);
  if (geo.valid) {
    // The same extent as the map's own grid, at the picture's pixel size.
    const double sx = double(mapGrid.cols) / m.mapWidth, sy = double(mapGrid.rows) / m.mapHeight;
    double gt[6] = {geo.geotransform[0], geo.geotransform[1] * sx, geo.geotransform[2] * sy,
                    geo.geotransform[3], geo.geotransform[4] * sx, geo.geotransform[5] * sy};
    if (err == CE_None) err = GDALSetGeoTransform(ds, gt);
    if (err == CE_None && !geo.crsWkt.empty()) err = GDALSetProjection(ds, geo.crsWkt.c_str());
  }
  GDALClose(ds);
  std::vector<std::uint8_t> bytes = takeMemFile(path);
  if (err != CE_None || bytes.empty())
    throw std::runtime_error(std::string("GeoTIFF export: ") + CPLGetLastErrorMsg());
  return bytes;
}

}  // namespace rover::maps
