#include "core/coverage/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "core/coverage/energy.hpp"
#include "core/coverage/plant.hpp"
#include "core/coverage/team_occupancy.hpp"
#include "core/grid/direction.hpp"

namespace rover::coverage {

Incident bumpIncident(const Bump& b, const GridGeometry& g) {
  const Eigen::Vector2d cell = cellToLocal(g, g.cell(b.cell));
  char note[160];
  std::snprintf(note, sizeof note, "step %lld: %s; the cell at (%.2f, %.2f) is now an obstacle in its map",
                static_cast<long long>(b.step),
                b.offField ? "the move would have left the field" : "drove into an obstacle its map held free",
                cell.x(), cell.y());
  Incident inc;
  inc.kind = IncidentKind::Bump;
  inc.rover = b.rover;
  inc.position = b.truePosition;
  inc.value = static_cast<double>(b.cell);
  inc.note = note;
  inc.step = b.step;
  inc.cause = b.offField ? "off_field" : "unmapped_obstacle";
  return inc;
}

void Recorder::bumped(const Bump& b) {
  if (!sink_) return;
  const Incident i = bumpIncident(b, g_);
  sink_->incidents({&i, 1}, false);
}

MoveEnergy::MoveEnergy(const EnergyModel& e, double cell)
    : e_(e), straight_(cell * 1.0), diagonal_(cell * std::numbers::sqrt2) {
  for (int from = 0; from < 8; ++from)
    for (int to = 0; to < 8; ++to) turn_[from][to] = turnEnergy(e, 0, std::abs(turnSteps(from, to)));
  flatStraight_ = forwardEnergy(e, straight_, 0.0);
  flatDiagonal_ = forwardEnergy(e, diagonal_, 0.0);
}

Recorder::Recorder(const World& world, const CoverageParams& params, EventSink* sink,
                   const std::vector<StartCell>& starts)
    : world_(world),
      g_(world.geometry()),
      p_(params),
      sink_(sink),
      energy_(params.energy, world.geometry().cellWidth),
      tracks_(starts.size()) {
  if (p_.recordTracks)
    for (std::size_t k = 0; k < starts.size(); ++k) tracks_[k].cells.push_back(starts[k].cell);
  // One curve point a step; a run to full coverage takes about as many steps as there are cells
  // (capped: a big map's run stops earlier or grows the vector as usual).
  curve_.reserve(static_cast<std::size_t>(std::min(g_.cellCount(), 1 << 20)) + 1);
}

void Recorder::emit(std::int64_t step, const TeamOccupancy& team, const Plant& plant,
                    const std::vector<CoverageRover>& rovers) {
  if (!changes_.empty()) sink_->cellsChanged(changes_);
  changes_.clear();
  poses_.clear();
  for (const CoverageRover& r : rovers) poses_.push_back(plant.pose(r));
  sink_->roverPoses(step, poses_);
  double needed = 0;
  for (const auto& m : team.maps())
    needed += std::max(1.0, std::ceil(p_.coverage * (m.regionCells() - m.knownObstacles()) - 1e-9));
  Progress pr;
  pr.step = step;
  pr.fraction = std::min(1.0, team.visitedTotal() / needed);
  pr.coverage = static_cast<double>(team.visitedTotal()) / world_.freeCount();
  pr.moves = moves();
  sink_->progress(pr);
}

CoverageResult Recorder::finish(StopReason stop, std::int64_t steps, TeamOccupancy& team, const Plant& plant) {
  CoverageResult res;
  res.stop = stop;
  CoverageMetrics& mt = res.metrics;
  mt.cells = g_.cellCount();
  mt.freeCells = world_.freeCount();
  mt.visitedCells = team.visitedTotal();
  mt.reachableCells = team.reachableCells(plant.visitedTrulyReached());
  mt.unreachableCells = mt.freeCells - mt.reachableCells;
  mt.coverage = static_cast<double>(mt.visitedCells) / mt.freeCells;
  mt.coverageReachable = static_cast<double>(mt.visitedCells) / std::max(1, mt.reachableCells);
  mt.steps = steps;
  for (const auto& t : tracks_) {
    mt.moves += t.moves;
    mt.makespan = std::max(mt.makespan, t.moves);
    mt.distanceM += t.distanceM;
    mt.energyJ += t.energyJ;
    mt.maxPitchDeg = std::max(mt.maxPitchDeg, t.maxPitchDeg);
    mt.revisits += t.revisits;
  }
  res.rovers = std::move(tracks_);
  mt.pathLengthRatio = static_cast<double>(mt.moves) / mt.cells;
  mt.makespanRatio = static_cast<double>(mt.makespan) / mt.cells;
  res.curve = std::move(curve_);
  team.finalView(res.finalStates, res.finalVisits);
  res.region = team.takeRegion();
  plant.summarise(res);
  return res;
}

}  // namespace rover::coverage
