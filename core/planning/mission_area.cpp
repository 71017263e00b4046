#include "core/planning/mission_area.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/common/error.hpp"

namespace rover {

namespace {

[[noreturn]] void refuse(const std::string& message) { throw Error(ErrorCode::InvalidInput, "area", message); }

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Twice the signed surface of a ring (shoelace).
double twiceSignedArea(const Ring& r) {
  double a = 0;
  for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++) a += r[j].x() * r[i].y() - r[i].x() * r[j].y();
  return a;
}

// Cell edges an area's bounding box lies on are taken exactly: 150 m on a 1 m grid is the
// border between columns 149 and 150, not a sliver of column 150. A millionth of a cell, in cells:
// a map's cell in metres comes from its CRS (0.4999999999458 m for a 0.5 m Mars equirectangular
// pixel), so 70 m is 140.0000000152 of them.
constexpr double kEdgeSlack = 1e-6;

}  // namespace

Eigen::Vector2d MissionArea::lo() const {
  Eigen::Vector2d v = Eigen::Vector2d::Constant(INFINITY);
  for (const auto& p : outline) v = v.cwiseMin(p);
  return v;
}

Eigen::Vector2d MissionArea::hi() const {
  Eigen::Vector2d v = Eigen::Vector2d::Constant(-INFINITY);
  for (const auto& p : outline) v = v.cwiseMax(p);
  return v;
}

MissionArea rectangleArea(double x0, double y0, double x1, double y1) {
  MissionArea a;
  a.outline = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  a.rectangle = true;
  return a;
}

MissionArea polygonArea(Ring outline) {
  MissionArea a;
  // A closing vertex repeated (as GeoJSON writes rings) is dropped: rings here are open.
  if (outline.size() > 1 && outline.front() == outline.back()) outline.pop_back();
  a.outline = std::move(outline);
  return a;
}

void checkMissionArea(const MissionArea& area, const GridGeometry& map, int marginCells) {
  const auto& ring = area.outline;
  if (!area.rectangle && (ring.size() < 3 || ring.size() > kMaxAreaVertices))
    refuse("a polygon area needs 3 to " + std::to_string(kMaxAreaVertices) + " vertices, not " +
           std::to_string(ring.size()));
  const double w = map.widthMetres(), h = map.heightMetres();
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto& p = ring[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) refuse("the area's coordinates must be finite numbers");
    const double tol = kEdgeSlack * std::min(map.cellWidth, map.cellHeight);
    if (p.x() < -tol || p.y() < -tol || p.x() > w + tol || p.y() > h + tol)
      refuse("the area's corner (" + num(p.x()) + ", " + num(p.y()) + ") m lies off the map (" + num(w) + " × " +
             num(h) + " m; local frame: metres from its lower-left corner)");
  }
  if (area.rectangle && !(ring[2].x() > ring[0].x() && ring[2].y() > ring[0].y()))
    refuse("the area's x1, y1 must be greater than its x0, y0");
  const Eigen::Vector2d size = area.hi() - area.lo();
  if (size.x() < 2 * map.cellWidth || size.y() < 2 * map.cellHeight)
    refuse("the area is " + num(size.x()) + " × " + num(size.y()) + " m: it must span at least 2 cells (" +
           num(2 * map.cellWidth) + " × " + num(2 * map.cellHeight) + " m) each way");
  if (!area.rectangle && std::fabs(twiceSignedArea(ring)) / 2 < 4 * map.cellWidth * map.cellHeight)
    refuse("the polygon's surface is under 4 cells (it is degenerate or self-cancelling)");
  const PlanningWindow win = planningWindow(map, area, marginCells);
  if (static_cast<std::int64_t>(win.grid.rows) * win.grid.cols > kMaxWindowCells)
    refuse("the area's planning window is " + std::to_string(win.grid.cols) + " × " + std::to_string(win.grid.rows) +
           " cells (with a margin of " + std::to_string(marginCells) + " cells), more than " +
           std::to_string(kMaxWindowCells) + " (4096 × 4096): choose a smaller area");
}

PlanningWindow wholeMap(const GridGeometry& map) {
  PlanningWindow w;
  w.grid = map;
  return w;
}

PlanningWindow planningWindow(const GridGeometry& map, const MissionArea& area, int marginCells) {
  const Eigen::Vector2d lo = area.lo(), hi = area.hi();
  const double height = map.heightMetres();
  // Columns from the west, rows from the north (SPEC §0): y = height is the top of row 0.
  auto clampTo = [](double v, int n) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(n))); };
  const int col0 = clampTo(std::floor(lo.x() / map.cellWidth + kEdgeSlack) - marginCells, map.cols);
  const int col1 = clampTo(std::ceil(hi.x() / map.cellWidth - kEdgeSlack) + marginCells, map.cols);
  const int row0 = clampTo(std::floor((height - hi.y()) / map.cellHeight + kEdgeSlack) - marginCells, map.rows);
  const int row1 = clampTo(std::ceil((height - lo.y()) / map.cellHeight - kEdgeSlack) + marginCells, map.rows);
  PlanningWindow w;
  w.row0 = row0;
  w.col0 = col0;
  w.grid = map;
  w.grid.rows = std::max(0, row1 - row0);
  w.grid.cols = std::max(0, col1 - col0);
  w.origin = {col0 * map.cellWidth, (map.rows - row1) * map.cellHeight};
  return w;
}

MissionArea areaInWindow(const MissionArea& area, const PlanningWindow& w) {
  MissionArea a = area;
  for (auto& p : a.outline) p -= w.origin;
  return a;
}

Polygon outsideArea(const MissionArea& a, const PlanningWindow& w) {
  const double cw = w.grid.cellWidth, ch = w.grid.cellHeight;
  const double x1 = w.grid.widthMetres() + cw, y1 = w.grid.heightMetres() + ch;
  Polygon p;
  p.push_back({{-cw, -ch}, {x1, -ch}, {x1, y1}, {-cw, y1}});
  p.push_back(a.outline);  // a hole by the even-odd rule
  return p;
}

std::vector<std::uint8_t> cellsInArea(const MissionArea& a, const GridGeometry& window) {
  // The complement of the keep-out rasterisation, so the PDM's mass lies exactly on the ground
  // the planners may drive (one rasterisation rule: polygonCells). The outer ring only needs to
  // cover the window.
  PlanningWindow w;
  w.grid = window;
  std::vector<std::uint8_t> out = polygonCells(window, {outsideArea(a, w)});
  for (auto& v : out) v = !v;
  return out;
}

void moveIntoWindow(std::vector<RoverStart>& rovers, KeepOut& keepOut, const PlanningWindow& w,
                    const MissionArea& area) {
  for (auto& r : rovers) r.position -= w.origin;
  for (auto& zone : keepOut.zones)
    for (auto& ring : zone)
      for (auto& p : ring) p -= w.origin;
  keepOut.zones.push_back(outsideArea(areaInWindow(area, w), w));
}

void shiftResult(PlanResult& r, const Eigen::Vector2d& by) {
  for (auto& t : r.tracks) {
    for (auto& p : t.points) p += by;
    for (auto& p : t.believed) p += by;
    for (auto& s : t.samples) s.position += by;
  }
  for (auto& t : r.targets) t.position += by;
  for (auto& o : r.overlays)
    for (auto& p : o.points) p += by;
  for (auto& i : r.incidents) i.position += by;
}

void ShiftedSink::roverPoses(std::int64_t step, std::span<const RoverPose> poses) {
  poses_.assign(poses.begin(), poses.end());
  for (auto& p : poses_) {
    p.x += by_.x();
    p.y += by_.y();
    p.believedX += by_.x();
    p.believedY += by_.y();
  }
  inner_.roverPoses(step, poses_);
}

void ShiftedSink::incidents(std::span<const Incident> found, bool complete) {
  incidents_.assign(found.begin(), found.end());
  for (auto& i : incidents_) i.position += by_;
  inner_.incidents(incidents_, complete);
}

void ShiftedSink::overlay(std::string_view kind, int rover, std::span<const Point2> points) {
  points_.assign(points.begin(), points.end());
  for (auto& p : points_) {
    p.x += by_.x();
    p.y += by_.y();
  }
  inner_.overlay(kind, rover, points_);
}

}  // namespace rover
