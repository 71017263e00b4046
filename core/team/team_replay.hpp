#pragma once
// A team mission streamed to an event sink while it runs, then replayed in mission time.
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/planning/planner.hpp"
#include "core/team/team_incidents.hpp"
#include "core/team/team_mission.hpp"

namespace rover::team {

// Forwards a team mission to an event sink: the route and the search cells as soon as the route
// is chosen, each rover's planned path as it is accepted, progress per leg; then, once every
// rover is simulated, a replay of the team's poses in time order and the search cells they
// enter, at one event per pose interval of mission time.
//
// Incidents go to the sink as they are found (issue 27): an attitude exceedance episode as soon
// as a committed piece closes it, a leg that did not reach when it is done; the planner then
// sends the complete list (collisions need the whole plan).
class SinkObserver final : public TeamObserver {
 public:
  // `starts`: each rover's start; `exceedanceLimit`: rad, the mission's exceedance_limit.
  SinkObserver(EventSink& sink, const std::vector<Pose>& starts, double exceedanceLimit) : sink_(sink) {
    for (std::size_t k = 0; k < starts.size(); ++k) {
      last_.emplace_back(starts[k].x, starts[k].y);
      scans_.emplace_back(static_cast<int>(k), exceedanceLimit);
    }
  }

  void routeChosen(const SearchGrid& grid, const Route& route) override {
    std::vector<Point2> pts{{route.startCentre.x(), route.startCentre.y()}};
    for (const auto& c : route.centres) pts.push_back({c.x(), c.y()});
    sink_.overlay("route", -1, pts);
    std::vector<CellUpdate> cells;
    for (int i = 0; i < grid.geometry().cellCount(); ++i)
      cells.push_back({i, static_cast<std::uint8_t>(grid.impassable.at(i) ? 2 : 1), 0});
    sink_.cellsChanged(cells);
  }
  void pieceAccepted(int rover, std::span<const Eigen::Vector2d> path,
                     std::span<const TrajectorySample> samples) override {
    std::vector<Point2> pts;
    for (std::size_t i = 1; i < path.size(); ++i) pts.push_back({path[i].x(), path[i].y()});
    if (!pts.empty()) sink_.overlay("path", rover, pts);
    if (rover < 0 || static_cast<std::size_t>(rover) >= scans_.size()) return;
    std::vector<Incident> found;
    for (const TrajectorySample& s : samples)
      if (auto i = scans_[rover].add(s)) found.push_back(std::move(*i));
    if (!samples.empty()) last_[rover] = {samples.back().x, samples.back().y};
    if (!found.empty()) sink_.incidents(found, false);
  }
  void legDone(const LegRecord& leg, int done, int total) override {
    if (leg.status != LegStatus::Reached && leg.rover >= 0 && static_cast<std::size_t>(leg.rover) < last_.size()) {
      const Incident i = legIncident(leg, last_[leg.rover]);
      sink_.incidents({&i, 1}, false);
    }
    replans_ += leg.replans;
    waits_ += leg.waits;
    Progress p;
    p.step = done;
    p.moves = done;
    p.fraction = total > 0 ? 0.9 * done / total : 0.9;
    p.phase = Progress::Phase::Planning;
    p.legsDone = done;
    p.legsTotal = total;
    p.replans = replans_;
    p.waits = waits_;
    sink_.progress(p);
  }

  void replay(const TeamMissionResult& r, double poseInterval, double period,
              const CancelToken* cancel) {
    const auto& traj = r.plan.trajectories;
    if (traj.empty()) return;
    std::size_t end = 0;
    for (const auto& t : traj) end = std::max(end, t.samples.size());
    const auto every = static_cast<std::size_t>(std::max(1L, std::lround(poseInterval / period)));
    const GridGeometry& g = r.grid.geometry();
    std::vector<std::uint32_t> visits(static_cast<std::size_t>(g.cellCount()), 0);
    std::vector<std::vector<std::uint8_t>> entered(traj.size(),
                                                   std::vector<std::uint8_t>(visits.size(), 0));
    int passable = 0, seen = 0;
    for (int i = 0; i < g.cellCount(); ++i) passable += r.grid.impassable.at(i) == 0;
    std::vector<RoverPose> poses(traj.size());
    std::vector<CellUpdate> changed;
    std::int64_t step = 0;
    double missionEnd = 0;
    for (const auto& t : traj)
      if (!t.samples.empty()) missionEnd = std::max(missionEnd, t.samples.back().time);
    for (std::size_t i = 0;; i = std::min(i + every, end - 1)) {
      if (cancel && cancel->cancelled()) return;
      changed.clear();
      for (std::size_t k = 0; k < traj.size(); ++k) {
        const auto& s = traj[k].samples[std::min(i, traj[k].samples.size() - 1)];
        poses[k] = {static_cast<int>(k), s.x, s.y, s.heading};
        const CellIndex cell = r.grid.cellAt({s.x, s.y});
        const int c = g.index(cell.row, cell.col);
        if (entered[k][c]) continue;
        entered[k][c] = 1;
        if (visits[c]++ == 0 && r.grid.impassable.at(c) == 0) ++seen;
        changed.push_back({c, 3, visits[c]});
      }
      if (!changed.empty()) sink_.cellsChanged(changed);
      sink_.roverPoses(step++, poses);
      Progress p;
      p.step = step;
      p.moves = static_cast<std::int64_t>(i);
      p.fraction = 0.9 + 0.1 * static_cast<double>(i + 1) / static_cast<double>(end);
      p.coverage = passable > 0 ? static_cast<double>(seen) / passable : 0.0;
      p.phase = Progress::Phase::Replay;
      p.replans = replans_;
      p.waits = waits_;
      p.missionTime = std::min(missionEnd, static_cast<double>(i) * period);
      p.missionEnd = missionEnd;
      sink_.progress(p);
      if (i + 1 >= end) break;
    }
  }

 private:
  EventSink& sink_;
  int replans_ = 0, waits_ = 0;
  std::vector<Eigen::Vector2d> last_;  // per rover: where its last committed sample lies
  std::vector<ExceedanceScan> scans_;  // per rover
};

}  // namespace rover::team
