#include "core/coverage/coverage_memory.hpp"

#include <algorithm>
#include <cstdio>

namespace rover::coverage {

namespace {

// Bytes per grid cell that do not depend on the rover count: world 9 (u8 obstacle, f64 height),
// resampled DEM 4, traversability while building 1, stream grid 5 and change log 8, planner
// occupancy 4, BFS parent/seen/queue 12, reachability 1 + its flood 5, final states and visits 5,
// one shared knowledge map 5.
constexpr std::uint64_t kPerCell = 59;
// Voronoi mode: a region index 4 per cell, and per rover a mask, a state and a visit count (6).
constexpr std::uint64_t kVoronoiPerCell = 4, kVoronoiPerRoverCell = 6;
// Per step: the planner's curve point 32 (up to twice that while its vector grows), the result's
// curve series 16, its JSON tree 32 and text ~30.
constexpr std::uint64_t kPerStep = 140;
// Per move: the stream's trail pose 12, the track's cell and pitch 8 and point 16, the pitch
// series 16, the result's JSON tree and text, the GeoJSON and the CSV while they are formatted.
// Measured: a 1-rover mission on the default map (360 000 cells, 459 582 moves) peaked 316 MB
// over the idle server, ~690 bytes a move and step together.
constexpr std::uint64_t kPerMove = 560;
// Localisation error (issue 15): per cell the true occupancy 4, true visits 1, last entry 8; per
// move the true and believed points 32 and the error 4 in the track, the stream's believed trail 8,
// the believed path and error series in the result's JSON tree and text (~250, as measured above
// for the path).
constexpr std::uint64_t kLocalisationPerCell = 13, kLocalisationPerMove = 300;

}  // namespace

StepBudget stepBudget(ParamSet& params, std::int64_t requested, std::int64_t cells, int rovers) {
  if (requested > 0) return {requested, true};  // 0 is the planner's "default": bounded below
  const std::int64_t n = std::max<std::int64_t>(cells, 1), k = std::max(rovers, 1);
  StepBudget b;
  b.steps = std::min(20 * n, (kDefaultMovesPerCell * n + k - 1) / k);
  params["max_steps"] = b.steps;
  return b;
}

MemoryEstimate missionMemory(std::int64_t cells, double cellSize, int rovers, bool voronoi, StepBudget steps,
                             bool localisation) {
  const auto n = static_cast<std::uint64_t>(std::max<std::int64_t>(cells, 0));
  const auto k = static_cast<std::uint64_t>(std::max(rovers, 1));
  std::uint64_t perCell = kPerCell;
  if (voronoi && k > 1) perCell += kVoronoiPerCell + kVoronoiPerRoverCell * k;
  if (localisation) perCell += kLocalisationPerCell;
  const std::uint64_t perMove = kPerMove + (localisation ? kLocalisationPerMove : 0);
  MemoryEstimate e;
  e.fixedBytes = kMissionFixedBytes + n * perCell;
  e.bytesPerStep = kPerStep + k * perMove;  // every rover moves at most once a step
  // In floating point: max_steps may be 1e9 with 64 rovers (the product overflows nothing there).
  const double bytes = static_cast<double>(e.fixedBytes) +
                       static_cast<double>(std::max<std::int64_t>(steps.steps, 0)) * static_cast<double>(e.bytesPerStep);
  e.bytes = bytes >= 1.8e19 ? ~0ull : static_cast<std::uint64_t>(bytes);
  char buf[200];
  std::snprintf(buf, sizeof buf, "%llu coverage cells of %g m, %llu rover%s%s, up to %lld steps",
                static_cast<unsigned long long>(n), cellSize, static_cast<unsigned long long>(k),
                k == 1 ? "" : "s", voronoi && k > 1 ? " (voronoi)" : "", static_cast<long long>(steps.steps));
  e.what = buf;
  // What to change: the steps the request asked for when they are what does not fit.
  e.field = steps.given && e.fixedBytes < e.bytes / 2 ? "params.max_steps" : "params.coverage_cell";
  return e;
}

}  // namespace rover::coverage
