#pragma once
// A team mission's incidents (PlanResult::incidents), made the same way for the result and for the
// live stream (team_replay.hpp reports them as they are found): every note states the limit that
// was hit, with its parameter name and value, and the value reached (issue 27: a note that named
// "the attitude limit" without values misled). Rovers are numbered from 1 in notes (people read
// them); the incident's fields keep the ids.
#include <Eigen/Core>
#include <cstddef>
#include <optional>

#include "core/planning/plan_result.hpp"
#include "core/team/coordination.hpp"
#include "core/team/rover_sim.hpp"
#include "core/team/separation.hpp"

namespace rover::team {

// Exceedance episodes of one rover's trajectory, fed sample by sample: consecutive samples with
// |roll| or |pitch| over `limit` (rad, the mission's exceedance_limit) make one incident, at the
// episode's first sample, with the worst angle.
class ExceedanceScan {
 public:
  ExceedanceScan(int rover, double limit) : rover_(rover), limit_(limit) {}
  // The episode this sample closes, if any.
  std::optional<Incident> add(const TrajectorySample& s);
  // The episode still open at the end of the trajectory, if any.
  std::optional<Incident> finish();

 private:
  Incident episode() const;
  int rover_;
  double limit_;
  std::size_t count_ = 0;  // samples of the open episode (0: none open)
  TrajectorySample first_;
  double worst_ = 0;
  bool worstPitch_ = false;
};

// A leg that did not reach its target (Short or Skipped), where the rover ended it.
Incident legIncident(const LegRecord& leg, const Eigen::Vector2d& at);
// Two rovers closer than `safetyDistance` (m) in the plan.
Incident collisionIncident(const Conflict& c, double safetyDistance);
// A route target where `rover` found no valid ground for its slot within half `footprint` (m)
// and, with `wholeCell` (timed mode, task_builder.cpp), none left anywhere in the search cell.
Incident noSlotIncident(int rover, int target, const Eigen::Vector2d& at, double footprint,
                        bool wholeCell = false);

}  // namespace rover::team
