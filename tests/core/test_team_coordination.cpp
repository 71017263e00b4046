// Prioritised multi-rover planning (SPEC §3.4) and the team mission (SPEC §3.5, §4).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/common/cancel.hpp"
#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/planner.hpp"
#include "core/team/coordination.hpp"
#include "core/team/coordinator.hpp"
#include "core/team/formation.hpp"
#include "core/team/team_entry.hpp"
#include "core/team/team_mission.hpp"
#include "core/terrain/layers.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;

namespace {

terrain::Dem flatDem(int rows, int cols) {
  return test::demFrom(rows, cols, 0.25, [](double, double) { return 0.0; });
}

// Gentle rolling ground (max slope ≈ 6°) so roll/pitch are exercised without blocking anything.
terrain::Dem rollingDem() {
  return test::demFrom(120, 120, 0.25, [](double x, double y) {
    return 0.35 * std::sin(x / 2.3) * std::cos(y / 3.1) + 0.02 * x;
  });
}

Raster<std::uint8_t> classesOf(const terrain::Dem& dem) {
  return terrain::traversability(dem).classes;
}

Trajectory line(Eigen::Vector2d from, Eigen::Vector2d to, int samples) {
  Trajectory t;
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector2d p = from + (to - from) * (static_cast<double>(i) / (samples - 1));
    TrajectorySample s;
    s.time = i * 0.1;
    s.x = p.x();
    s.y = p.y();
    t.samples.push_back(s);
  }
  return t;
}

}  // namespace

TEST_CASE("team: checkSeparation finds each close episode once and the closest approach") {
  // Two rovers on the same line in opposite directions meet in the middle at sample 50.
  std::vector<Trajectory> t{line({0, 0}, {10, 0}, 101), line({10, 0}, {0, 0}, 101)};
  SeparationReport r = checkSeparation(t, 1.0);
  REQUIRE(r.conflicts.size() == 1);
  CHECK(r.conflicts[0].rover == 1);
  CHECK(r.conflicts[0].other == 0);
  CHECK(r.minimumDistance == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(r.minimumTime == doctest::Approx(5.0));
  // Closer than 1 m from |10 − 0.2·i| < 1, i.e. samples 46..54: the episode starts at 4.6 s.
  CHECK(r.conflicts[0].time == doctest::Approx(4.6));
  // Parallel lines 2 m apart never conflict.
  std::vector<Trajectory> apart{line({0, 0}, {10, 0}, 101), line({0, 2}, {10, 2}, 101)};
  SeparationReport q = checkSeparation(apart, 1.0);
  CHECK(q.conflicts.empty());
  CHECK(q.minimumDistance == doctest::Approx(2.0));
  // A parked rover is an obstacle: rover 1 stops at (5, 0) after 1 sample; rover 0 drives through.
  std::vector<Trajectory> parked{line({0, 0}, {10, 0}, 101), line({5, 0}, {5, 0}, 2)};
  CHECK(checkSeparation(parked, 1.0).conflicts.size() == 1);
}

namespace {
// The scan the traffic table replaces: every sample index, every rover in priority order.
std::optional<Conflict> scanConflict(const std::vector<Trajectory>& others, int rover,
                                     std::size_t index, const Eigen::Vector2d& p, double safety) {
  for (std::size_t j = 0; j < others.size(); ++j) {
    const Eigen::Vector2d o = positionAtIndex(others[j], index);
    if ((p - o).norm() < safety)
      return Conflict{rover, static_cast<int>(j), static_cast<double>(index) * 0.1, index, 0.0,
                      (p - o).norm(), p, o};
  }
  return std::nullopt;
}

// A random walk of `n` samples at up to 0.03 m per sample (a rover's 0.3 m/s at 10 Hz), parking
// when it ends, inside a 6 × 6 m square so paths cross often.
Trajectory walk(Rng& rng, std::size_t n) {
  Trajectory t;
  Eigen::Vector2d p(rng.uniform() * 6, rng.uniform() * 6);
  for (std::size_t i = 0; i < n; ++i) {
    TrajectorySample s;
    s.time = static_cast<double>(i) * 0.1;
    p += Eigen::Vector2d(rng.uniform() - 0.5, rng.uniform() - 0.5) * 0.06;
    p = p.cwiseMax(0.0).cwiseMin(6.0);
    s.x = p.x();
    s.y = p.y();
    t.samples.push_back(s);
  }
  return t;
}
}  // namespace

TEST_CASE("team: the traffic table answers exactly what a sample-by-sample scan answers") {
  // Four committed rovers of different lengths (so some are parked while others move), a fifth
  // driving or standing from many start indices: the first conflict (index, then rover) and its
  // fields must be the scan's, including none.
  Rng rng(11);
  std::vector<Trajectory> others;
  for (std::size_t n : {300u, 45u, 170u, 1u}) others.push_back(walk(rng, n));
  TrafficTable table(1.0, 0.1);
  for (const auto& t : others) table.add(t);
  CHECK(table.rovers() == 4);
  CHECK(table.end() == 300);
  int conflicts = 0, clear = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Trajectory mine = walk(rng, 1 + static_cast<std::size_t>(rng.uniform() * 120));
    const auto from = static_cast<std::size_t>(rng.uniform() * 330);
    std::optional<Conflict> expected;
    for (std::size_t m = 0; m < mine.samples.size() && !expected; ++m)
      expected = scanConflict(others, 4, from + m, {mine.samples[m].x, mine.samples[m].y}, 1.0);
    const auto got = table.driving(4, mine.samples, from);
    REQUIRE(got.has_value() == expected.has_value());
    if (got) {
      ++conflicts;
      CHECK(got->other == expected->other);
      CHECK(got->time == expected->time);
      CHECK(got->index == expected->index);
      CHECK(got->distance == expected->distance);
      CHECK(got->otherPosition == expected->otherPosition);
    } else {
      ++clear;
    }
    // Standing at the walk's end over [from, from + 37).
    const Eigen::Vector2d p(mine.samples.back().x, mine.samples.back().y);
    std::optional<Conflict> still;
    for (std::size_t i = from; i < from + 37 && !still; ++i) still = scanConflict(others, 4, i, p, 1.0);
    const auto stood = table.standing(4, p, from, from + 37);
    REQUIRE(stood.has_value() == still.has_value());
    if (stood) {
      CHECK(stood->index == still->index);
      CHECK(stood->other == still->other);
      CHECK(stood->distance == still->distance);
    }
  }
  // Both answers were exercised.
  CHECK(conflicts > 20);
  CHECK(clear > 20);
}

TEST_CASE("team: a head-on pair is forced to re-plan and the plan is collision-free") {
  const terrain::Dem dem = flatDem(80, 160);  // 40 × 20 m
  const auto classes = classesOf(dem);
  std::vector<RoverTask> tasks(2);
  // Each goal 5 m short of the other's start: a rover standing at its start holds that spot until
  // it leaves (issue 25), so a goal on it would be a swap no priority order can plan.
  tasks[0].start = {5, 10, 0};
  tasks[0].legs.push_back({{30, 10}, {}, 0});
  tasks[1].start = {35, 10, M_PI};
  tasks[1].legs.push_back({{10, 10}, {}, 0});
  CoordinationParams p;
  p.threads = 2;
  CoordinationResult r = coordinate(dem, classes, tasks, p, 7);
  // Without coordination the two straight RRT* paths meet head-on; rover 1 must re-plan.
  CHECK(r.replans > 0);
  CHECK(r.conflicts.empty());
  SeparationReport sep = checkSeparation(r.trajectories, p.safetyDistance);
  CHECK(sep.conflicts.empty());
  CHECK(sep.minimumDistance >= p.safetyDistance);
  REQUIRE(r.legs.size() == 2);
  CHECK(r.legs[0].status == LegStatus::Reached);
  CHECK(r.legs[0].replans == 0);  // the first rover is never disturbed
  CHECK(r.legs[1].status == LegStatus::Reached);
  CHECK(r.legs[1].replans > 0);
  // Both really arrive.
  CHECK((Eigen::Vector2d(r.trajectories[0].samples.back().x, r.trajectories[0].samples.back().y) -
         Eigen::Vector2d(30, 10)).norm() < 0.5);
  CHECK((Eigen::Vector2d(r.trajectories[1].samples.back().x, r.trajectories[1].samples.back().y) -
         Eigen::Vector2d(10, 10)).norm() < 0.5);
}

TEST_CASE("team: with no re-plans allowed a crossing rover waits, then goes") {
  const terrain::Dem dem = flatDem(120, 120);  // 30 × 30 m
  const auto classes = classesOf(dem);
  std::vector<RoverTask> tasks(2);
  tasks[0].start = {2, 15, 0};
  tasks[0].legs.push_back({{28, 15}, {}, 0});
  // Rover 1 crosses rover 0's line at (15, 15) at about the same time.
  tasks[1].start = {15, 2, M_PI / 2};
  tasks[1].legs.push_back({{15, 28}, {}, 0});
  CoordinationParams p;
  p.maxReplans = 0;
  p.waitStep = 5.0;
  CoordinationResult r = coordinate(dem, classes, tasks, p, 3);
  REQUIRE(r.legs.size() == 2);
  CHECK(r.legs[1].waits > 0);
  CHECK(r.legs[1].status == LegStatus::Reached);
  CHECK(r.conflicts.empty());
  // The wait is at the start: rover 1's first samples stay put.
  const auto& s = r.trajectories[1].samples;
  CHECK(s[10].x == doctest::Approx(15.0));
  CHECK(s[10].y == doctest::Approx(2.0));
}

TEST_CASE("team: a goal on impassable ground is skipped and reported, the rest goes on") {
  // A 60° ramp in the east third of the map is impassable.
  const terrain::Dem dem = test::demFrom(80, 120, 0.25, [](double x, double) {
    return x > 20 ? (x - 20) * std::tan(60 * M_PI / 180) : 0.0;
  });
  const auto classes = classesOf(dem);
  std::vector<RoverTask> tasks(1);
  tasks[0].start = {3, 10, 0};
  tasks[0].legs.push_back({{27, 10}, {}, 0});  // on the ramp
  tasks[0].legs.push_back({{10, 15}, {}, 1});
  CoordinationResult r = coordinate(dem, classes, tasks, CoordinationParams{}, 1);
  REQUIRE(r.legs.size() == 2);
  CHECK(r.legs[0].status == LegStatus::Skipped);
  CHECK(r.legs[0].reason == LegReason::InvalidGoal);
  CHECK(r.legs[0].note.find("invalid_goal") != std::string::npos);
  CHECK(r.legs[1].status == LegStatus::Reached);
  CHECK(r.legs[1].reason == LegReason::None);
}

TEST_CASE("team: bad coordination parameters name the field") {
  const terrain::Dem dem = flatDem(20, 20);
  const auto classes = classesOf(dem);
  std::vector<RoverTask> tasks(1);
  tasks[0].start = {2, 2, 0};
  CoordinationParams p;
  p.safetyDistance = -1;
  try {
    coordinate(dem, classes, tasks, p, 1);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "safety_distance");
  }
  p = {};
  p.maxReplans = -2;
  CHECK_THROWS_AS(coordinate(dem, classes, tasks, p, 1), Error);
  // A start off the map names the rover.
  tasks[0].start = {-5, 2, 0};
  try {
    coordinate(dem, classes, tasks, CoordinationParams{}, 1);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "rovers[0]");
  }
}

TEST_CASE("team: formation slots for five rovers are the centre and the four corners") {
  auto s = formationSlots(5, 5.0);
  REQUIRE(s.size() == 5);
  CHECK(s[0].norm() == doctest::Approx(0.0));
  for (int k = 1; k < 5; ++k) {
    CHECK(std::abs(s[k].x()) == doctest::Approx(5.0 / 3));
    CHECK(std::abs(s[k].y()) == doctest::Approx(5.0 / 3));
  }
  // Pairwise apart by more than the safety distance, all inside the footprint.
  for (std::size_t a = 0; a < s.size(); ++a) {
    CHECK(s[a].cwiseAbs().maxCoeff() < 2.5);
    for (std::size_t b = a + 1; b < s.size(); ++b) CHECK((s[a] - s[b]).norm() > 1.0);
  }
  CHECK(formationSlots(1, 5.0).size() == 1);
  CHECK(formationSlots(9, 5.0).size() == 9);
}

TEST_CASE("team: start slots keep two safety distances and a lane apart, five rovers as before") {
  // Issue 25: disjoint safety discs round the standing rovers, so every one can drive out.
  CHECK(startSlots(5, 5.0, 1.0) == formationSlots(5, 5.0));  // 2.36 m apart already
  for (int n : {10, 20, 40, 64}) {
    const auto s = startSlots(n, 5.0, 1.0);
    REQUIRE(static_cast<int>(s.size()) == n);
    double nearest = 1e9;
    for (std::size_t a = 0; a < s.size(); ++a)
      for (std::size_t b = a + 1; b < s.size(); ++b) nearest = std::min(nearest, (s[a] - s[b]).norm());
    CHECK(nearest == doctest::Approx(startSpacing(1.0)));
  }
}

TEST_CASE("team: accumulated probability is the PDM mass under the sensed discs") {
  // Uniform PDM over 20 × 20 m; one rover drives 10 m along y = 10 sensing a 1 m disc.
  const terrain::Dem dem = flatDem(80, 80);
  const Raster<float> pdm = uniformPdm(dem);
  std::vector<Trajectory> t{line({5, 10}, {15, 10}, 1001)};
  for (std::size_t i = 0; i < t[0].samples.size(); ++i) t[0].samples[i].distance = i * 0.01;
  ProbabilityCurves c = accumulatedProbability(pdm, t, 1.0);
  REQUIRE(!c.team.empty());
  // A 10 m × 1 m strip plus two half discs ≈ 10.785 m² of 400 m²; on 0.25 m cells the count of
  // centres within 0.5 m of the segment is close to that.
  CHECK(c.team.back().second == doctest::Approx(10.785 / 400).epsilon(0.06));
  CHECK(c.team.back().first == doctest::Approx(10.0));
  CHECK(c.single.back().second == doctest::Approx(c.team.back().second));
  // Monotone.
  for (std::size_t i = 1; i < c.team.size(); ++i) CHECK(c.team[i].second >= c.team[i - 1].second);
}

TEST_CASE("team: a whole mission is collision-free and the same for a seed") {
  const terrain::Dem dem = rollingDem();  // 30 × 30 m
  TeamMissionParams p;
  p.route.targets = 6;
  p.coordination.threads = 2;
  const Raster<float> pdm = uniformPdm(dem);
  std::vector<Pose> starts{{12, 12, 0}, {15, 12, 0}, {12, 15, 0}};
  TeamMissionResult a = runTeamMission(dem, pdm, starts, p, false);
  TeamMissionResult b = runTeamMission(dem, pdm, starts, p, false);
  CHECK(a.metrics.collisions == 0);
  CHECK(a.plan.conflicts.empty());
  CHECK(a.metrics.targets == 6);
  CHECK(a.metrics.targetsReached + a.metrics.targetsSkipped + a.metrics.targetsShort == 18);
  CHECK(a.metrics.targetsReached >= 15);
  CHECK(a.metrics.meanTrajectoryM > 0);
  CHECK(a.metrics.samples > 0);
  CHECK(a.metrics.accumulatedProbability > 0);
  CHECK(a.metrics.accumulatedProbability >= a.metrics.singleRoverProbability);
  REQUIRE(a.plan.trajectories.size() == b.plan.trajectories.size());
  for (std::size_t k = 0; k < a.plan.trajectories.size(); ++k) {
    const auto &sa = a.plan.trajectories[k].samples, &sb = b.plan.trajectories[k].samples;
    REQUIRE(sa.size() == sb.size());
    for (std::size_t i = 0; i < sa.size(); ++i) {
      CHECK(sa[i].x == sb[i].x);
      CHECK(sa[i].y == sb[i].y);
    }
  }
  // The same on one thread: the look-ahead planning is parallel, the result is not thread-bound.
  p.coordination.threads = 1;
  TeamMissionResult one = runTeamMission(dem, pdm, starts, p, false);
  for (std::size_t k = 0; k < a.plan.trajectories.size(); ++k) {
    const auto &sa = a.plan.trajectories[k].samples, &so = one.plan.trajectories[k].samples;
    REQUIRE(sa.size() == so.size());
    for (std::size_t i = 0; i < sa.size(); ++i) CHECK(sa[i].x == so[i].x);
  }
  // Another seed plans other trees.
  p.seed = 2;
  TeamMissionResult c = runTeamMission(dem, pdm, starts, p, false);
  bool differs = c.plan.trajectories[0].samples.size() != a.plan.trajectories[0].samples.size();
  for (std::size_t i = 0; !differs && i < c.plan.trajectories[0].samples.size(); ++i)
    differs = c.plan.trajectories[0].samples[i].x != a.plan.trajectories[0].samples[i].x;
  CHECK(differs);
}

TEST_CASE("team: a 3×3 block at the safety distance leaves without a collision, the same on 1 and 2 threads") {
  // Issue 25: nine rovers on a 1 m lattice (exactly the safety distance) on rolling ground. Every
  // rover stands at its start until it is planned, and the centre one, boxed in, is planned after
  // its neighbours: no collision, and the plan does not depend on the threads.
  const terrain::Dem dem = rollingDem();  // 30 × 30 m
  TeamMissionParams p;
  p.route.targets = 2;
  const Raster<float> pdm = uniformPdm(dem);
  std::vector<Pose> starts;
  for (int k = 0; k < 9; ++k) starts.push_back({14.0 + k % 3, 14.0 + k / 3, 0});
  p.coordination.threads = 2;
  const TeamMissionResult two = runTeamMission(dem, pdm, starts, p, false);
  CHECK(two.metrics.collisions == 0);
  CHECK(two.plan.conflicts.empty());
  p.coordination.threads = 1;
  const TeamMissionResult one = runTeamMission(dem, pdm, starts, p, false);
  REQUIRE(one.plan.trajectories.size() == two.plan.trajectories.size());
  for (std::size_t k = 0; k < one.plan.trajectories.size(); ++k) {
    const auto &a = one.plan.trajectories[k].samples, &b = two.plan.trajectories[k].samples;
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      CHECK(a[i].x == b[i].x);
      CHECK(a[i].y == b[i].y);
    }
  }
}

TEST_CASE("team: a rover whose goal lies past a formation's top row against a wall plans round the standing rovers at once") {
  // Issue 25, the Kepler site with 40 rovers: the formation's top row stood 0.75 m under the
  // crater wall, and a rover at its west end had its first goal just past the row's east end.
  // The rovers planned after it stand at their starts for the whole of its plan; the planner saw
  // them only one conflict at a time (a keep-out zone per try), spent the re-plans on them and
  // the leg ended 6.6 m short. Timed: every plan keeps out of the standing rovers' starts from
  // the first try (ConflictPolicy::standingKeepOut), so the first plan goes round the block.
  const terrain::Dem dem = test::demFromPicture({
      "##############################",
      "##############################",
      "##############################",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
  });  // 30 × 20 m, the wall's foot at y = 17
  const Raster<std::uint8_t> classes = classesOf(dem);
  CoordinationParams p;
  p.threads = 1;
  // Two rows of five at the generated formation's spacing (2.25 m), the top row 1 m under the
  // wall: none may pass north of another. Rover 0, at the top row's west end, leaves first.
  std::vector<RoverTask> tasks;
  for (int row = 0; row < 2; ++row)
    for (int c = 0; c < 5; ++c) tasks.push_back({{6.0 + 2.25 * c, 16.0 - 2.25 * row, 0.0}, {}});
  tasks[0].legs.push_back({{17.5, 16.0}, {}, 0});
  const TimedPolicy timed(p);
  CHECK(timed.standingKeepOut() == doctest::Approx(p.safetyDistance + planning::kDepartureMargin / 2));
  CHECK(PaperPolicy(p).standingKeepOut() == 0.0);  // the paper mode meets them by its conflicts
  const CoordinationResult r = coordinate(dem, classes, tasks, p, 3);
  REQUIRE(r.legs.size() == 1);
  CHECK(r.legs[0].status == LegStatus::Reached);
  CHECK(r.legs[0].replans == 0);  // the first plan already went round
  CHECK(r.conflicts.empty());
  // Every waypoint of the rover's path keeps the zone's radius from the standing rovers.
  for (const Eigen::Vector2d& w : r.paths[0])
    for (std::size_t j = 1; j < tasks.size(); ++j)
      CHECK((w - Eigen::Vector2d(tasks[j].start.x, tasks[j].start.y)).norm() >= timed.standingKeepOut() - 1e-9);
}

TEST_CASE("team: the hybrid mission covers each footprint and senses more of it") {
  const terrain::Dem dem = rollingDem();
  TeamMissionParams p;
  p.route.targets = 3;
  const Raster<float> pdm = uniformPdm(dem);
  std::vector<Pose> starts{{12, 12, 0}, {15, 12, 0}};
  TeamMissionResult search = runTeamMission(dem, pdm, starts, p, false);
  TeamMissionResult hybrid = runTeamMission(dem, pdm, starts, p, true);
  CHECK(hybrid.metrics.collisions == 0);
  // Same route, more legs (the coverage moves) and more sensed mass.
  CHECK(hybrid.route.cells == search.route.cells);
  CHECK(hybrid.plan.legs.size() > search.plan.legs.size());
  CHECK(hybrid.metrics.accumulatedProbability > search.metrics.accumulatedProbability);
}

TEST_CASE("team: the registered planners validate, run and report the issue's metrics") {
  PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("team-search");
  CHECK_NOTHROW(reg.get("hybrid"));
  PlanningProblem problem;
  problem.rovers = {{{12, 12}, 0.0}, {{15, 12}, 0.0}};
  // No DEM.
  try {
    planner.validate(problem, {});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "map");
  }
  problem.dem = std::make_shared<terrain::Dem>(rollingDem());
  ParamSet params{{"targets", std::int64_t{3}}};
  CHECK_NOTHROW(planner.validate(problem, params));
  // Unknown and out-of-range parameters name the key.
  try {
    planner.validate(problem, {{"targetz", std::int64_t{3}}});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "targetz");
  }
  try {
    planner.validate(problem, {{"safety_distance", -1.0}});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "safety_distance");
  }
  // Two rovers closer than the safety distance.
  PlanningProblem close = problem;
  close.rovers[1].position = {12.5, 12};
  try {
    planner.validate(close, params);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "rovers[1]");
  }
  // A PDM on another grid.
  PlanningProblem wrongPdm = problem;
  wrongPdm.pdm = std::make_shared<Raster<float>>(GridGeometry{10, 10, 1, 1}, 0.01f);
  try {
    planner.validate(wrongPdm, params);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "pdm");
  }
  // The event grid is the search grid: 30 m / 5 m.
  GridGeometry eg = planner.eventGrid(problem, params);
  CHECK(eg.rows == 6);
  CHECK(eg.cols == 6);
  CHECK(eg.cellWidth == 5.0);
  PlanResult r = planner.run(problem, params, nullptr, nullptr);
  for (const char* key : {"mean_trajectory_m", "mission_time_s", "samples", "exceedances",
                          "exceedance_fraction", "collisions", "min_separation_m",
                          "accumulated_probability", "targets_reached", "targets_skipped",
                          "plan_wall_s"})
    CHECK_NOTHROW(r.metric(key));
  CHECK(r.metric("collisions") == 0);
  CHECK(r.tracks.size() == 2);
  REQUIRE(!r.overlays.empty());
  CHECK(r.overlays[0].key == "route");
  CHECK(r.overlays[0].points.size() == 4);  // the start and 3 targets
}

namespace {
struct RecordingSink : EventSink {
  int routes = 0, paths = 0, poses = 0, metricEvents = 0, cells = 0;
  double lastFraction = 0;
  void overlay(std::string_view kind, int, std::span<const Point2>) override {
    (kind == "route" ? routes : paths)++;
  }
  void roverPoses(std::int64_t, std::span<const RoverPose>) override { ++poses; }
  void metrics(std::span<const Metric>) override { ++metricEvents; }
  void cellsChanged(std::span<const CellUpdate> c) override { cells += static_cast<int>(c.size()); }
  void progress(const Progress& p) override { lastFraction = p.fraction; }
};
struct CancelAfterRoute : EventSink {
  CancelToken* token;
  explicit CancelAfterRoute(CancelToken* t) : token(t) {}
  void overlay(std::string_view, int, std::span<const Point2>) override { token->cancel(); }
};
}  // namespace

TEST_CASE("team: events stream the route, each accepted path, poses and metrics, cancel stops") {
  PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("team-search");
  PlanningProblem problem;
  problem.dem = std::make_shared<terrain::Dem>(rollingDem());
  problem.rovers = {{{12, 12}, 0.0}, {{15, 12}, 0.0}};
  ParamSet params{{"targets", std::int64_t{3}}, {"pose_interval", 2.0}};
  RecordingSink sink;
  PlanResult r = planner.run(problem, params, &sink, nullptr);
  CHECK(sink.routes == 1);
  CHECK(sink.paths >= 6);  // 2 rovers × 3 legs
  CHECK(sink.metricEvents == 1);
  CHECK(sink.cells >= 36);  // the whole search grid once, then the cells entered
  // One pose event per 2 s of mission time (plus the last).
  CHECK(sink.poses >= r.metric("mission_time_s") / 2.0);
  CHECK(sink.poses <= r.metric("mission_time_s") / 2.0 + 2);
  CHECK(sink.lastFraction == doctest::Approx(1.0));

  CancelToken token;
  CancelAfterRoute canceller(&token);
  PlanResult c = planner.run(problem, params, &canceller, &token);
  CHECK(c.cancelled);
}

TEST_CASE("rrt: keep-out zones are never entered, and a goal inside one is invalid") {
  const terrain::Dem dem = flatDem(80, 160);
  const auto classes = classesOf(dem);
  std::vector<KeepOutZone> zones{{{20, 10}, 2.0}};
  RrtParams rp;
  rp.clearance = 5;  // room to go round the 2 m disc
  PathResult r = planPath(dem, classes, {5, 10}, 0, {35, 10}, rp, {}, nullptr, zones);
  REQUIRE(r.status == PathStatus::Exact);
  // Every vertex and every point along every edge stays out of the disc.
  for (std::size_t i = 0; i + 1 < r.waypoints.size(); ++i)
    for (int s = 0; s <= 20; ++s) {
      const Eigen::Vector2d p = r.waypoints[i] + (r.waypoints[i + 1] - r.waypoints[i]) * (s / 20.0);
      CHECK((p - zones[0].centre).norm() > 2.0 - 1e-9);
    }
  CHECK(planPath(dem, classes, {5, 10}, 0, {20.5, 10}, rp, {}, nullptr, zones).status ==
        PathStatus::InvalidGoal);
}

TEST_CASE("rrt: a vertex must be safe at every heading (turnValid), an edge only along it") {
  // A 14.5° plane rising to the east: within a 15° limit whichever way the rover faces... and a
  // cross slope combining 11° east and 11° north, whose full slope (15.4°) exceeds 15° though
  // each axis alone does not.
  const double t = std::tan(11 * M_PI / 180);
  const terrain::Dem dem = test::demFrom(40, 40, 0.25, [t](double x, double y) { return t * (x + y); });
  const auto classes = Raster<std::uint8_t>(dem.geometry(), 0);  // all traversable
  const GridGeometry& g = dem.geometry();
  TerrainEdgeModel m(dem, classes, {{0, 0}, {g.widthMetres(), g.heightMetres()}},
                     15 * M_PI / 180, 0.05);
  CHECK(m.pointValid({5, 5}));
  CHECK_FALSE(m.turnValid({5, 5}));
  // Driving straight east: pitch 11°, roll 11° — a valid edge.
  CHECK(m.edgeValid({3, 5}, {7, 5}));
}

TEST_CASE("team: edge_evaluation auto is paper 001's sampling in the paper mode, the exact patch form in the timed mode") {
  CoordinationParams p;
  CHECK(p.rrt.evaluation == EdgeEvaluation::Auto);
  p.mode = CoordinationMode::Paper;
  CHECK(resolveEvaluation(p).rrt.evaluation == EdgeEvaluation::Sampled);
  p.mode = CoordinationMode::Timed;
  CHECK(resolveEvaluation(p).rrt.evaluation == EdgeEvaluation::Patch);
  // A stated choice is kept in either mode.
  p.rrt.evaluation = EdgeEvaluation::Sampled;
  CHECK(resolveEvaluation(p).rrt.evaluation == EdgeEvaluation::Sampled);
  p.mode = CoordinationMode::Paper;
  p.rrt.evaluation = EdgeEvaluation::Patch;
  CHECK(resolveEvaluation(p).rrt.evaluation == EdgeEvaluation::Patch);
  // Through the parameter table: the key, its values, and a refusal naming it.
  CHECK(parseTeamParams({{"edge_evaluation", std::string("patch")}}).mission.coordination.rrt.evaluation ==
        EdgeEvaluation::Patch);
  CHECK(parseTeamParams({}).mission.coordination.rrt.evaluation == EdgeEvaluation::Auto);
  try {
    (void)parseTeamParams({{"edge_evaluation", std::string("exact")}});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "edge_evaluation");
  }
}
