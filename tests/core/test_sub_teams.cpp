// Sub-teams for larger teams (issue 25, core/team/sub_teams.hpp): the split of the rovers and of
// the route, the slot builder flying one formation per sub-team, and a mission of seven rovers on
// a drawn flat site.
#include <doctest/doctest.h>

#include <algorithm>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "core/planning/departure.hpp"
#include "core/team/formation.hpp"
#include "core/team/sub_teams.hpp"
#include "core/team/task_builder.hpp"
#include "core/team/team_mission.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;

namespace {

// Starts on a lattice of `cols` columns, 3 m apart, from (x0, y0).
std::vector<Pose> lattice(int n, int cols, double x0, double y0) {
  std::vector<Pose> out;
  for (int i = 0; i < n; ++i) out.push_back({x0 + 3.0 * (i % cols), y0 + 3.0 * (i / cols), 0});
  return out;
}

Route routeThrough(const std::vector<Eigen::Vector2d>& centres) {
  Route r;
  r.centres = centres;
  for (std::size_t i = 0; i < centres.size(); ++i) r.cells.push_back({0, static_cast<int>(i)});
  return r;
}

// Every rover in exactly one sub-team of at most `size`; ofRover and rovers agree; each sub-team's
// targets one contiguous run.
void checkPartition(const SubTeams& s, int n, int targets, int size) {
  REQUIRE(static_cast<int>(s.ofRover.size()) == n);
  REQUIRE(static_cast<int>(s.ofTarget.size()) == targets);
  std::vector<int> seen(static_cast<std::size_t>(n), 0);
  for (int g = 0; g < s.count(); ++g) {
    CHECK(static_cast<int>(s.rovers[g].size()) <= size);
    CHECK(std::is_sorted(s.rovers[g].begin(), s.rovers[g].end()));
    for (int r : s.rovers[g]) {
      ++seen[static_cast<std::size_t>(r)];
      CHECK(s.ofRover[static_cast<std::size_t>(r)] == g);
    }
  }
  for (int c : seen) CHECK(c == 1);
  for (int t = 1; t < targets; ++t) CHECK(s.ofTarget[t] >= s.ofTarget[t - 1]);
}

}  // namespace

TEST_CASE("sub-teams: sizes as equal as possible, at most the size, one team at or below it") {
  CHECK(subTeamSizes(5, 5) == std::vector<int>{5});
  CHECK(subTeamSizes(3, 5) == std::vector<int>{3});
  CHECK(subTeamSizes(6, 5) == std::vector<int>{3, 3});
  CHECK(subTeamSizes(11, 5) == std::vector<int>{4, 4, 3});
  CHECK(subTeamSizes(20, 0) == std::vector<int>{20});
  CHECK(subTeamSizes(0, 5).empty());
  const std::vector<int> s64 = subTeamSizes(64, 5);
  CHECK(s64.size() == 13);
  CHECK(std::accumulate(s64.begin(), s64.end(), 0) == 64);
  CHECK(*std::max_element(s64.begin(), s64.end()) == 5);
  CHECK(*std::min_element(s64.begin(), s64.end()) == 4);
}

TEST_CASE("sub-teams: every rover in exactly one sub-team of at most five, neighbours together") {
  // Ten rovers in two rows of five, 3 m apart: by angle round the centroid the northern row comes
  // first (east to west), then the southern one, so each row is one wedge; 64 targets split into
  // two contiguous runs of 32.
  const std::vector<Pose> starts = lattice(10, 5, 10, 10);
  std::vector<Eigen::Vector2d> targets;
  for (int t = 0; t < 64; ++t) targets.emplace_back(40 + t, 12.5);
  const SubTeams s = splitTeam(starts, targets, 5);
  REQUIRE(s.count() == 2);
  checkPartition(s, 10, 64, 5);
  CHECK(std::count(s.ofTarget.begin(), s.ofTarget.end(), 0) == 32);
  // The route starts nearer the northern row (y 13) than the southern one (y 10): the first
  // segment goes to the northern wedge.
  for (int r : s.rovers[0]) CHECK(starts[r].y == 13);
  for (int r : s.rovers[1]) CHECK(starts[r].y == 10);
  // 64 rovers on an 8 × 8 lattice, 30 targets: 13 sub-teams, every one with targets.
  const SubTeams big = splitTeam(lattice(64, 8, 5, 5), std::vector<Eigen::Vector2d>(30, {50, 50}), 5);
  CHECK(big.count() == 13);
  checkPartition(big, 64, 30, 5);
  CHECK(std::set<int>(big.ofTarget.begin(), big.ofTarget.end()).size() == 13);
  // Fewer targets than sub-teams: the last ones get none. Size 0 or ≥ N: one team, everything.
  const SubTeams few = splitTeam(lattice(12, 4, 5, 5), {{30, 30}, {31, 30}}, 5);
  checkPartition(few, 12, 2, 5);
  CHECK(few.ofTarget == std::vector<int>{0, 1});
  const SubTeams one = splitTeam(lattice(12, 4, 5, 5), targets, 0);
  CHECK(one.count() == 1);
  CHECK(one.rovers[0].size() == 12);
  CHECK(std::all_of(one.ofTarget.begin(), one.ofTarget.end(), [](int g) { return g == 0; }));
}

TEST_CASE("sub-teams: the slot builder flies one formation per sub-team, never sharing a target or a slot") {
  // A flat 24 × 24 m site, 8 rovers in two sub-teams of four, 4 targets along y = 16.
  const terrain::Dem dem = test::demFromPicture(std::vector<std::string>(24, std::string(24, '.')));
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  const std::vector<Pose> starts = lattice(8, 4, 4, 3);
  const Route route = routeThrough({{4, 16}, {9, 16}, {14, 16}, {19, 16}});
  const SubTeams s = splitTeam(starts, route.centres, 4);
  REQUIRE(s.count() == 2);
  const std::vector<RoverTask> tasks = SlotTasks(dem, classes, p, nullptr, &s).build(starts, route, nullptr);
  REQUIRE(tasks.size() == 8);
  std::vector<std::set<int>> teamsAt(route.centres.size());
  std::vector<Eigen::Vector2d> goals;
  for (int k = 0; k < 8; ++k) {
    CHECK(tasks[k].legs.size() == 2);  // the two targets of its sub-team's segment
    for (const Leg& l : tasks[k].legs) {
      CHECK(s.ofTarget[static_cast<std::size_t>(l.target)] == s.ofRover[k]);
      teamsAt[static_cast<std::size_t>(l.target)].insert(s.ofRover[k]);
      for (const auto& g : goals) CHECK((g - l.goal).norm() > 1e-6);  // no slot used twice
      goals.push_back(l.goal);
    }
  }
  for (const auto& t : teamsAt) CHECK(t.size() == 1);
  // One team (no split): every rover at every target, as paper 001.
  const std::vector<RoverTask> all = SlotTasks(dem, classes, p, nullptr).build(starts, route, nullptr);
  for (const RoverTask& t : all) CHECK(t.legs.size() == 4);
}

TEST_CASE("sub-teams: a slot whose search cell lies among the starts gets ground outside the formation") {
  // Issue 25, the Kepler site with 40 rovers: a target's search cell overlapped the formation, and
  // all its free ground lay within the goal spacing plus the departure margin of rovers that leave
  // after the sub-team's (the task builder keeps goals that far from them): 3 slots had no ground.
  // Here 20 rovers stand on the generated formation's 2.25 m lattice on flat ground and the first
  // target's cell lies inside the block: every ground point of it is 1.6 m or less from a start.
  const terrain::Dem dem = test::demFromPicture(std::vector<std::string>(30, std::string(30, '.')));
  const auto classes = terrain::traversability(dem).classes;
  TeamMissionParams p;
  std::vector<Pose> starts;
  for (int i = 0; i < 20; ++i) starts.push_back({10 + 2.25 * (i % 5), 10 + 2.25 * (i / 5), 0});
  const Route route = routeThrough({{14.5, 13.375}, {14.5, 22}, {22, 22}, {22, 14.5}});
  const SubTeams s = splitTeam(starts, route.centres, 5);
  REQUIRE(s.count() == 4);
  const std::vector<RoverTask> tasks = SlotTasks(dem, classes, p, nullptr, &s).build(starts, route, nullptr);
  // The coordinator's order (departure.hpp): which starts still stand when each rover is planned.
  std::vector<Eigen::Vector2d> at;
  for (const Pose& st : starts) at.emplace_back(st.x, st.y);
  const planning::Departure d = planning::departureOrder(at, p.coordination.safetyDistance);
  REQUIRE(d.boxedIn.empty());
  std::vector<int> rank(starts.size());
  for (std::size_t r = 0; r < d.order.size(); ++r) rank[static_cast<std::size_t>(d.order[r])] = static_cast<int>(r);
  const double clear = goalSpacing(p.coordination) + planning::kDepartureMargin;
  const std::vector<int>& team = s.rovers[static_cast<std::size_t>(s.ofTarget[0])];
  std::vector<Eigen::Vector2d> goals;
  for (int k : team) {
    CAPTURE(k);
    const auto leg = std::find_if(tasks[k].legs.begin(), tasks[k].legs.end(), [](const Leg& l) { return l.target == 0; });
    REQUIRE(leg != tasks[k].legs.end());  // a slot for every rover of the sub-team
    // Clear of every rover still standing when it gets there, and of its team mates' goals.
    for (std::size_t j = 0; j < starts.size(); ++j)
      if (rank[j] > rank[static_cast<std::size_t>(k)]) CHECK((leg->goal - at[j]).norm() >= clear - 1e-9);
    for (const auto& g : goals) CHECK((leg->goal - g).norm() >= goalSpacing(p.coordination) - 1e-9);
    goals.push_back(leg->goal);
    // Near the target all the same: within one and a half footprints of its centre.
    CHECK((leg->goal - route.centres[0]).norm() <= 1.5 * p.footprint + 1e-9);
  }
}

TEST_CASE("sub-teams: a mission of seven rovers splits in two, 0 collisions, same plan on 1 and 2 threads") {
  const terrain::Dem dem = test::demFrom(160, 160, 0.25, [](double, double) { return 0.0; });
  TeamMissionParams p;
  p.route.targets = 4;
  p.coordination.rrt.maxVertices = 400;
  const std::vector<Pose> starts = lattice(7, 4, 14, 14);
  p.coordination.threads = 1;
  const TeamMissionResult a = runTeamMission(dem, uniformPdm(dem), starts, p, false);
  p.coordination.threads = 2;
  const TeamMissionResult b = runTeamMission(dem, uniformPdm(dem), starts, p, false);
  REQUIRE(a.subTeams.count() == 2);
  checkPartition(a.subTeams, 7, static_cast<int>(a.route.cells.size()), 5);
  CHECK(a.metrics.collisions == 0);
  CHECK(a.noSlot.empty());
  for (const LegRecord& l : a.plan.legs)
    if (l.target >= 0)
      CHECK(a.subTeams.ofTarget[static_cast<std::size_t>(l.target)] == a.subTeams.ofRover[static_cast<std::size_t>(l.rover)]);
  // Every target visited by its sub-team's formation: 4 + 3 rovers over 2 + 2 targets.
  CHECK(a.metrics.targetsReached + a.metrics.targetsSkipped + a.metrics.targetsShort == 14);
  CHECK(b.subTeams.ofRover == a.subTeams.ofRover);
  REQUIRE(b.plan.trajectories.size() == a.plan.trajectories.size());
  for (std::size_t k = 0; k < a.plan.trajectories.size(); ++k) {
    REQUIRE(b.plan.trajectories[k].samples.size() == a.plan.trajectories[k].samples.size());
    CHECK(b.plan.trajectories[k].samples.back().x == a.plan.trajectories[k].samples.back().x);
    CHECK(b.plan.trajectories[k].samples.back().y == a.plan.trajectories[k].samples.back().y);
  }
  // The paper coordination keeps paper 001's single team.
  p.coordination.mode = CoordinationMode::Paper;
  p.route.targets = 1;
  CHECK(runTeamMission(dem, uniformPdm(dem), starts, p, false).subTeams.count() == 1);
}
