#pragma once
// The mission area (issue 24): the part of a big map a mission plans in. Planning cost should
// follow the mission, not the map: the traversal lattice (9 bytes a map cell), the reachability
// flood, the guides, the PDM and the classes of a team mission, or a coverage grid, are built on
// a planning window — the area's bounding box plus a margin, at the map's full resolution — not
// on the whole map. The planners themselves know nothing of it: they plan on the window as if it
// were the map (its own local frame, origin at its lower-left corner), and the caller moves what
// goes in (rover starts, keep-out zones) into the window's frame and what comes out (tracks,
// targets, incidents, overlays, event poses) back into the map's.
//
// Ground of the window outside the area is keep-out (core/planning/keep_out.hpp), so every
// planner's own keep-out rule holds the rovers inside: coverage counts it as obstacles, the team
// planners class it KeepOut (never a target, never driven on).
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/grid/geometry.hpp"
#include "core/planning/events.hpp"
#include "core/planning/keep_out.hpp"
#include "core/planning/plan_result.hpp"
#include "core/planning/planner.hpp"

namespace rover {

// A rectangle or a polygon (one ring, no holes) in the map's local frame.
struct MissionArea {
  Ring outline;            // open ring (closing vertex not repeated)
  bool rectangle = false;  // given as x0, y0, x1, y1 (outline holds its four corners)
  Eigen::Vector2d lo() const;  // bounding box
  Eigen::Vector2d hi() const;
};

// Limits (stated in README, "Mission area"):
// - the planning window (area + margin) holds at most kMaxWindowCells cells (4096², 16.8 M: a
//   team mission there peaks near what a whole 600² default map costs ×47, about 1 GB);
// - a map of more than kWholeMapCells cells needs an area (the same 4096²: above it a whole-map
//   mission's lattice and floods alone cost more than 150 MB and seconds before any leg);
// - a polygon has 3 to kMaxAreaVertices vertices.
inline constexpr std::int64_t kMaxWindowCells = 4096ll * 4096;
inline constexpr std::int64_t kWholeMapCells = 4096ll * 4096;
inline constexpr std::size_t kMaxAreaVertices = 1024;
// The margin around the area's bounding box, in cells: the 3×3 slope kernel's halo (1 cell) so the
// area's edge cells get their true slopes and classes, plus the ring of keep-out ground a
// coverage rover senses (sensing radius ≤ 2 cells by default) and the team planners' keep-out
// margin reads, so neither sees the window's own edge before the area's.
inline constexpr int kAreaMarginCells = 4;

MissionArea rectangleArea(double x0, double y0, double x1, double y1);
MissionArea polygonArea(Ring outline);

// Throws Error(InvalidInput, "area") unless every vertex is finite and on the map (0 ≤ x ≤ width,
// 0 ≤ y ≤ height), the area spans at least 2 cells each way and has a positive surface (a polygon:
// 3 to kMaxAreaVertices vertices, shoelace area ≥ 4 cells), and its window fits kMaxWindowCells.
void checkMissionArea(const MissionArea& area, const GridGeometry& map, int marginCells = kAreaMarginCells);

// A window of the map: rows row0..row0+grid.rows-1, columns col0..col0+grid.cols-1 (row 0 north),
// with the map's cell sizes. `origin` is the map-local position of its lower-left corner, so a
// point p of the map is p − origin in the window's frame.
struct PlanningWindow {
  int row0 = 0, col0 = 0;
  GridGeometry grid;
  Eigen::Vector2d origin{0, 0};
  bool covers(const GridGeometry& map) const { return grid.rows == map.rows && grid.cols == map.cols; }
};

// The whole map as a window (origin 0).
PlanningWindow wholeMap(const GridGeometry& map);
// The cells the area's bounding box touches, grown by `marginCells` on each side and clipped to
// the map.
PlanningWindow planningWindow(const GridGeometry& map, const MissionArea& area,
                              int marginCells = kAreaMarginCells);

// The area in the window's frame.
MissionArea areaInWindow(const MissionArea& area, const PlanningWindow& w);
// The ground of the window outside the area, as one keep-out zone in the window's frame: the
// window's outline grown by a cell (so its edge cells are wholly inside) with the area as a hole.
Polygon outsideArea(const MissionArea& areaInWindowFrame, const PlanningWindow& w);
// Cells of the window whose centre lies inside the area (row-major, 1 = inside): where the
// PDM's mass may lie.
std::vector<std::uint8_t> cellsInArea(const MissionArea& areaInWindowFrame, const GridGeometry& window);

// Rover starts and keep-out zones given in the map's frame moved into the window's, and the
// ground outside the area added as one more zone (outsideArea), in place.
void moveIntoWindow(std::vector<RoverStart>& rovers, KeepOut& keepOut, const PlanningWindow& w,
                    const MissionArea& area);

// Moves every position of a result by `by` (the window's origin: window frame → map frame).
void shiftResult(PlanResult& result, const Eigen::Vector2d& by);

// An event sink that hands positions on moved by `by` (window frame → map frame); cell indices
// stay the window grid's (the stream says where that grid lies).
class ShiftedSink final : public EventSink {
 public:
  ShiftedSink(EventSink& inner, const Eigen::Vector2d& by) : inner_(inner), by_(by) {}
  void cellsChanged(std::span<const CellUpdate> cells) override { inner_.cellsChanged(cells); }
  void roverPoses(std::int64_t step, std::span<const RoverPose> poses) override;
  void progress(const Progress& p) override { inner_.progress(p); }
  void overlay(std::string_view kind, int rover, std::span<const Point2> points) override;
  void metrics(std::span<const Metric> metrics) override { inner_.metrics(metrics); }
  void incidents(std::span<const Incident> found, bool complete) override;

 private:
  EventSink& inner_;
  Eigen::Vector2d by_;
  std::vector<RoverPose> poses_;  // reused buffers
  std::vector<Point2> points_;
  std::vector<Incident> incidents_;
};

}  // namespace rover
