#pragma once
// The task builder stage: the legs of each rover along the team route. Two builders:
// - SlotTasks (paper 001 §3.6): at every target, the target centre plus the rover's formation
//   slot, moved to the nearest valid point (RRT* validity, at least the safety distance from the
//   team mates' goals) within half a footprint when it is not; timed, else the free ground
//   nearest the target in its search cell, and with sub-teams, when the cell's free ground all
//   lies among the starts of rovers that leave later, the nearest outside them up to 1.5
//   footprints from the target (task_builder.cpp); a target with no such point gives that rover
//   no leg there. With the orienteering route in timed mode (ours), the slots are first turned
//   to the heading of the leg reaching the target (laneTurn, formation.hpp) so each rover sweeps
//   its own lane.
// - HybridTasks (SPEC §4): the slot leg above and then the rover's moves of a myopic coverage run
//   (Laîné & Yoshida / Santra et al., SPEC §1, frontier mode, heights for β) over the footprint
//   from the slots, as fixed points.
// `reachable` (non-null): goals only on cells marked 1 (TraversalLattice::reachable).
// `teams` (non-null, sub_teams.hpp): each target gets the formation of its own sub-team only (the
// slots of that sub-team's size, in its rovers' order); the other rovers get no leg there. Null:
// one team, every rover at every target (paper 001).
#include <cstdint>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/grid/raster.hpp"
#include "core/team/coordination.hpp"
#include "core/team/mission_params.hpp"
#include "core/team/route_search.hpp"
#include "core/team/sub_teams.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

class TaskBuilder {
 public:
  virtual ~TaskBuilder() = default;
  // One task per start, in priority order. Throws InvalidInput "rovers" for 0 or more than 64.
  virtual std::vector<RoverTask> build(const std::vector<Pose>& starts, const Route& route,
                                       const CancelToken* cancel) const = 0;
};

// The ground and the parameters both builders read (references: they must outlive the builder).
class GroundTaskBuilder : public TaskBuilder {
 public:
  GroundTaskBuilder(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                    const TeamMissionParams& params, const Raster<std::uint8_t>* reachable,
                  const SubTeams* teams = nullptr)
      : dem_(dem), classes_(classes), params_(params), reachable_(reachable), teams_(teams) {}

 protected:
  const terrain::Dem& dem_;
  const Raster<std::uint8_t>& classes_;
  const TeamMissionParams& params_;
  const Raster<std::uint8_t>* reachable_;
  const SubTeams* teams_;
};

class SlotTasks final : public GroundTaskBuilder {
 public:
  using GroundTaskBuilder::GroundTaskBuilder;
  std::vector<RoverTask> build(const std::vector<Pose>& starts, const Route& route,
                               const CancelToken* cancel) const override;
};

class HybridTasks final : public GroundTaskBuilder {
 public:
  using GroundTaskBuilder::GroundTaskBuilder;
  std::vector<RoverTask> build(const std::vector<Pose>& starts, const Route& route,
                               const CancelToken* cancel) const override;
};

// The same as free functions.
std::vector<RoverTask> teamSearchTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                       const std::vector<Pose>& starts, const Route& route,
                                       const TeamMissionParams& params,
                                       const Raster<std::uint8_t>* reachable = nullptr,
                                       const CancelToken* cancel = nullptr,
                                       const SubTeams* teams = nullptr);
std::vector<RoverTask> hybridTasks(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   const std::vector<Pose>& starts, const Route& route,
                                   const TeamMissionParams& params, const CancelToken* cancel,
                                   const Raster<std::uint8_t>* reachable = nullptr,
                                   const SubTeams* teams = nullptr);

// Throws InvalidInput "rovers" unless there are 1 to 64 starts.
void requireStarts(const std::vector<Pose>& starts);

}  // namespace rover::team
