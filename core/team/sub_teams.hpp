#pragma once
// Sub-teams for larger teams (issue 25, after paper 001's own suggestion: its prioritised planning
// "may not be inherently scalable to larger robotic teams"; it names hierarchical sub-teams). A team
// of N rovers splits into K = ⌈N / size⌉ sub-teams of at most `size` rovers, sizes as equal as
// possible (they differ by at most one). Rovers are assigned by their starts: sorted by the angle of
// their start round the team's centroid (ties by distance, then index) and cut into K consecutive
// runs, so each sub-team is a wedge of neighbouring starts and the sub-teams leave the formation in
// different directions. The route's targets are cut the same way into K contiguous segments (sizes
// as equal as possible), and segment k goes to the sub-team whose start centroid is nearest to the
// segment's first target, in segment order. Each sub-team then flies paper 001's formation (at most
// `size` slots) round the targets of its own segment only: no two sub-teams share a target or a
// slot, and a target's mass is searched by one sub-team, not by all N rovers. The cost of a mission
// is then close to that of one sub-team over the whole route (legs ≈ targets × size, not
// targets × N) plus one transit leg per rover to its segment. Pure, deterministic.
#include <Eigen/Core>
#include <vector>

#include "core/team/rover_sim.hpp"

namespace rover::team {

struct SubTeams {
  std::vector<int> ofRover;                // sub-team of each rover (index into `rovers`)
  std::vector<std::vector<int>> rovers;    // the rovers of each sub-team, ascending (their priority)
  std::vector<int> ofTarget;               // sub-team that visits each route target
  int count() const { return static_cast<int>(rovers.size()); }
};

// The sizes of ⌈n / size⌉ sub-teams of at most `size`, as equal as possible, larger ones first
// (size ≤ 0 or ≥ n: one team of n). n = 0: none.
std::vector<int> subTeamSizes(int n, int size);

// The split described above for the rovers at `starts` and the route targets at `targets` (their
// centres, in visiting order). size ≤ 0 or ≥ the number of rovers: one sub-team holding every rover
// and every target (paper 001's single team, unchanged).
SubTeams splitTeam(const std::vector<Pose>& starts, const std::vector<Eigen::Vector2d>& targets,
                   int size);

}  // namespace rover::team
