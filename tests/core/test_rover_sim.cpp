#include "core/team/rover_sim.hpp"
#include "core/team/separation.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include "core/common/error.hpp"
#include "dem_literals.hpp"

using namespace rover;
using namespace rover::team;

namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kRadPerDeg = kPi / 180.0;

using rover::test::demFrom;

// 20 × 20 m at 0.25 m.
terrain::Dem flat20() {
  return demFrom(80, 80, 0.25, [](double, double) { return 1.0; });
}

Trajectory run(const terrain::Dem& dem, std::vector<Eigen::Vector2d> wps, Pose start,
               const SlipParams& slip = {}, double startTime = 0.0,
               const ControllerParams& ctl = {}) {
  return simulate(dem, wps, start, startTime, RoverModel{}, ctl, slip);
}

// First time after which |speed − target| stays within tol until `until` (exclusive).
double settlingTime(const Trajectory& t, double target, double tol, double until) {
  double settled = std::numeric_limits<double>::quiet_NaN();
  for (const auto& s : t.samples) {
    if (s.time >= until) break;
    if (std::abs(s.speed - target) > tol)
      settled = std::numeric_limits<double>::quiet_NaN();
    else if (std::isnan(settled))
      settled = s.time;
  }
  return settled;
}

}  // namespace

TEST_CASE("sim: straight line on flat ground settles at the nominal speed, sampled at 10 Hz") {
  const terrain::Dem dem = flat20();
  const double t0 = 12.3;
  Trajectory t = run(dem, {{17.0, 10.0}}, {2.0, 10.0, 0.0}, {}, t0);
  REQUIRE(t.status == SimStatus::Reached);
  CHECK(t.waypointsReached == 1);
  REQUIRE(t.samples.size() > 100);

  // Exactly 10 Hz: sample k at startTime + k × 0.1 s.
  CHECK(t.samplePeriod == 0.1);
  for (std::size_t k = 0; k < t.samples.size(); ++k)
    CHECK(t.samples[k].time == doctest::Approx(t0 + 0.1 * static_cast<double>(k)).epsilon(1e-12));

  // Starts at rest, settles to 0.3 m/s within 2 % in a few seconds and stays there.
  CHECK(t.samples.front().speed == 0.0);
  const double end = t.samples.back().time;
  const double settle2 = settlingTime(t, 0.3, 0.006, end) - t0;
  const double settle05 = settlingTime(t, 0.3, 0.0015, end) - t0;
  MESSAGE("settling to ±2 %: " << settle2 << " s, to ±0.5 %: " << settle05 << " s");
  CHECK(settle2 < 3.0);
  CHECK(settle05 < 5.0);
  double peak = 0;
  for (const auto& s : t.samples) peak = std::max(peak, s.speed);
  MESSAGE("peak speed " << peak << " m/s");
  CHECK(peak < 0.3 * 1.1);

  // Straight along the line: heading and cross-track error stay at 0.
  for (const auto& s : t.samples) {
    CHECK(std::abs(s.heading) < 1e-9);
    CHECK(std::abs(s.y - 10.0) < 1e-9);
    CHECK(s.roll == 0.0);
    CHECK(s.pitch == 0.0);
  }
  // Ends at the goal: inside the acceptance circle plus at most one braking tick.
  const auto& last = t.samples.back();
  const double miss = (Eigen::Vector2d(last.x, last.y) - Eigen::Vector2d(17.0, 10.0)).norm();
  MESSAGE("end " << miss << " m from the goal after " << trajectoryDuration(t) << " s, "
                 << trajectoryLength(t) << " m");
  CHECK(miss <= ControllerParams{}.acceptanceRadius + 0.01);
  CHECK(trajectoryLength(t) == doctest::Approx(last.x - 2.0).epsilon(1e-9));
  CHECK(trajectoryDuration(t) == doctest::Approx(0.1 * (t.samples.size() - 1)));
  // 15 m at ≈0.3 m/s.
  CHECK(trajectoryDuration(t) > 14.75 / 0.3);
  CHECK(trajectoryDuration(t) < 14.75 / 0.3 + 2.0);
}

TEST_CASE("sim: heading error from a wrong initial heading goes to zero") {
  const terrain::Dem dem = flat20();
  Trajectory t = run(dem, {{18.0, 10.0}}, {2.0, 10.0, 0.6});
  REQUIRE(t.status == SimStatus::Reached);
  double settled = -1;
  for (const auto& s : t.samples)
    if (std::abs(s.heading) > 0.01) settled = s.time;
  // The rover turns onto the line within a couple of seconds; the remaining approach follows the
  // line-of-sight law's own convergence, cross-track error decaying at ≈ speed / lookahead.
  MESSAGE("heading within 0.01 rad of the path for good after " << settled << " s");
  CHECK(settled < 10.0);
  const auto& last = t.samples.back();
  CHECK(std::abs(last.heading) < 1e-3);
  CHECK(std::abs(last.y - 10.0) < 1e-3);
  // No oscillation about the line: after the first overshoot the offset keeps one sign.
  for (const auto& s : t.samples)
    if (s.time > 2.0) CHECK(s.y >= 10.0);
}

TEST_CASE("sim: a 90-degree turn stays close to the corner") {
  const terrain::Dem dem = flat20();
  const ControllerParams ctl;
  Trajectory t = run(dem, {{10.0, 2.0}, {10.0, 12.0}}, {2.0, 2.0, 0.0});
  REQUIRE(t.status == SimStatus::Reached);
  CHECK(t.waypointsReached == 2);
  double maxX = 0, maxCross = 0;
  for (const auto& s : t.samples) {
    maxX = std::max(maxX, s.x);
    if (s.y > 3.0) maxCross = std::max(maxCross, std::abs(s.x - 10.0));
  }
  MESSAGE("past the corner line x = 10: " << maxX - 10.0 << " m; off the second leg after y = 3: "
                                          << maxCross << " m");
  // Switched at the acceptance circle, so x ≈ 9.75 at the switch; the turn may carry it a little
  // past the corner line, but not much beyond the acceptance radius.
  CHECK(maxX - 10.0 < 0.5 * ctl.acceptanceRadius);
  CHECK(maxCross < 0.1);
  const auto& last = t.samples.back();
  CHECK((Eigen::Vector2d(last.x, last.y) - Eigen::Vector2d(10.0, 12.0)).norm() <=
        ctl.acceptanceRadius + 0.01);
}

TEST_CASE("sim: on a slope the speed drops and roll/pitch match the plane") {
  // z = 0.1·x + 0.15·y: ∇h = (0.1, 0.15).
  const Eigen::Vector2d grad(0.1, 0.15);
  const terrain::Dem dem =
      demFrom(80, 80, 0.25, [&](double x, double y) { return grad.x() * x + grad.y() * y; });
  const ControllerParams ctl;
  for (double dir : {0.0, kPi / 2, kPi / 4, -3 * kPi / 4}) {
    CAPTURE(dir);
    const Eigen::Vector2d c(10.0, 10.0), d(std::cos(dir), std::sin(dir));
    Trajectory t = run(dem, {c + 7.0 * d}, {c.x() - 7.0 * d.x(), c.y() - 7.0 * d.y(), dir});
    REQUIRE(t.status == SimStatus::Reached);
    const double pitch = std::atan(grad.dot(d));
    const double roll = std::atan(grad.dot(Eigen::Vector2d(-d.y(), d.x())));
    const double tilt = std::max(std::abs(pitch), std::abs(roll));
    const double expected =
        0.3 * (1.0 - (1.0 - ctl.speedFloor) * std::min(tilt / ctl.slopeForFloor, 1.0));
    for (const auto& s : t.samples) {
      // Roll and pitch at every sample: the analytic plane for the sample's own heading.
      const Eigen::Vector2d h(std::cos(s.heading), std::sin(s.heading));
      CHECK(s.pitch == doctest::Approx(std::atan(grad.dot(h))).epsilon(1e-5));
      CHECK(s.roll == doctest::Approx(std::atan(grad.dot(Eigen::Vector2d(-h.y(), h.x())))).epsilon(1e-5));
    }
    const auto& mid = t.samples[t.samples.size() / 2];
    CHECK(mid.pitch == doctest::Approx(pitch).epsilon(1e-5));
    CHECK(mid.roll == doctest::Approx(roll).epsilon(1e-5));
    // Slower than on flat ground, settled at the slope-aware speed despite gravity (the
    // integral of the surge PID removes the droop).
    MESSAGE("heading " << dir << ": pitch " << inDegrees(mid).pitch << "°, roll " << inDegrees(mid).roll
                       << "°, speed " << mid.speed << " (expected " << expected << ")");
    CHECK(expected < 0.3);
    CHECK(mid.speed == doctest::Approx(expected).epsilon(0.01));
  }
}

TEST_CASE("sim: slip drifts the rover down the cross slope, reproducibly per seed") {
  // Rising to the north at 0.25 (14°); driving east the ground rises to the left: roll > 0, and
  // slip pushes the rover south.
  const terrain::Dem dem = demFrom(80, 80, 0.25, [](double, double y) { return 0.25 * y; });
  const std::vector<Eigen::Vector2d> wps{{18.0, 10.0}};
  const Pose start{2.0, 10.0, 0.0};
  Trajectory dry = run(dem, wps, start);
  SlipParams slip;
  slip.enabled = true;
  slip.seed = 7;
  Trajectory a = run(dem, wps, start, slip), a2 = run(dem, wps, start, slip);
  slip.seed = 8;
  Trajectory b = run(dem, wps, start, slip);
  REQUIRE(dry.status == SimStatus::Reached);
  REQUIRE(a.status == SimStatus::Reached);
  REQUIRE(b.status == SimStatus::Reached);

  double dryMax = 0, meanOffset = 0, minY = 10.0;
  for (const auto& s : dry.samples) dryMax = std::max(dryMax, std::abs(s.y - 10.0));
  for (const auto& s : a.samples) {
    meanOffset += s.y - 10.0;
    minY = std::min(minY, s.y);
  }
  meanOffset /= static_cast<double>(a.samples.size());
  MESSAGE("slip: mean lateral offset " << meanOffset << " m, largest " << 10.0 - minY
                                       << " m; without slip " << dryMax << " m");
  CHECK(dryMax < 1e-9);
  CHECK(meanOffset < -0.02);  // downhill = south
  CHECK(10.0 - minY > 0.05);
  // Ground distance includes the sideways part, so it exceeds the dry run's.
  CHECK(trajectoryLength(a) > trajectoryLength(dry) - 0.3);

  // Same seed: identical, sample for sample. Another seed: different.
  REQUIRE(a.samples.size() == a2.samples.size());
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    CHECK(a.samples[k].x == a2.samples[k].x);
    CHECK(a.samples[k].y == a2.samples[k].y);
    CHECK(a.samples[k].heading == a2.samples[k].heading);
    CHECK(a.samples[k].speed == a2.samples[k].speed);
  }
  bool differs = a.samples.size() != b.samples.size();
  for (std::size_t k = 0; !differs && k < a.samples.size(); ++k)
    differs = a.samples[k].y != b.samples[k].y;
  CHECK(differs);
}

TEST_CASE("sim: exceedance counting on a steep ramp") {
  // Flat up to x = 10, then a 20° ramp.
  const double rise = std::tan(20.0 * kRadPerDeg);
  const terrain::Dem dem = demFrom(80, 80, 0.25, [&](double x, double) {
    return x < 10.0 ? 0.0 : rise * (x - 10.0);
  });
  Trajectory t = run(dem, {{18.0, 10.0}}, {2.0, 10.0, 0.0});
  REQUIRE(t.status == SimStatus::Reached);
  AttitudeExceedance e = attitudeExceedance(t);
  CHECK(e.samples == t.samples.size());
  std::size_t onRamp = 0;
  for (const auto& s : t.samples) {
    if (s.x < 9.6) CHECK(std::abs(s.pitch) < 1e-9);
    if (s.x > 10.2) {
      ++onRamp;
      CHECK(s.pitch == doctest::Approx(20.0 * kRadPerDeg).epsilon(1e-4));
    }
  }
  MESSAGE(e.count << " of " << e.samples << " samples over 15° (" << onRamp << " past x = 10.2)");
  CHECK(e.count >= onRamp);
  CHECK(e.count <= onRamp + 5);  // the one-cell bilinear transition
  CHECK(e.fraction() == doctest::Approx(static_cast<double>(e.count) / e.samples));
  CHECK(attitudeExceedance(t, 25.0 * kRadPerDeg).count == 0);

  // Strictly greater than the limit, either angle, either sign.
  Trajectory h;
  for (double deg : {10.0, 16.0, -16.0, 15.0}) {
    TrajectorySample p, r;
    p.pitch = deg * kRadPerDeg;
    r.roll = deg * kRadPerDeg;
    h.samples.push_back(p);
    h.samples.push_back(r);
  }
  CHECK(attitudeExceedance(h).count == 4);
  CHECK(attitudeExceedance(h).fraction() == 0.5);
  CHECK(attitudeExceedance(Trajectory{}).fraction() == 0.0);
}

TEST_CASE("sim: separation of simulated rovers crossing, on time and one delayed") {
  // Two rovers crossing at (10, 10) at the same time, then one held 10 s at its start: on the
  // team's shared 10 Hz clock (separation.hpp) a delay is samples standing still first.
  const terrain::Dem dem = flat20();
  Trajectory east = run(dem, {{18.0, 10.0}}, {2.0, 10.0, 0.0});
  Trajectory north = run(dem, {{10.0, 18.0}}, {10.0, 2.0, kPi / 2});
  const SeparationReport cross = checkSeparation({east, north}, 1.0);
  MESSAGE("crossing: " << cross.minimumDistance << " m at t = " << cross.minimumTime << " s");
  CHECK(cross.minimumDistance < 0.05);
  CHECK(cross.conflicts.size() == 1);
  Trajectory delayed = north;
  delayed.samples.insert(delayed.samples.begin(), 100, north.samples.front());
  const SeparationReport apart = checkSeparation({east, delayed}, 1.0);
  MESSAGE("delayed 10 s: " << apart.minimumDistance << " m at t = " << apart.minimumTime << " s");
  CHECK(apart.minimumDistance > 2.0);
  CHECK(apart.conflicts.empty());
}

TEST_CASE("sim: statuses for the time limit, leaving the map and cancellation") {
  const terrain::Dem dem = flat20();
  ControllerParams ctl;
  ctl.timeLimit = 2.0;
  Trajectory tl = run(dem, {{18.0, 10.0}}, {2.0, 10.0, 0.0}, {}, 0.0, ctl);
  CHECK(tl.status == SimStatus::TimeLimit);
  CHECK(tl.samples.size() == 21);
  CHECK(trajectoryDuration(tl) == doctest::Approx(2.0));
  CHECK(enumName(tl.status) == "time_limit");

  Trajectory off = run(dem, {{25.0, 10.0}}, {15.0, 10.0, 0.0});
  CHECK(off.status == SimStatus::LeftMap);
  CHECK(off.samples.back().x <= 20.0);
  CHECK(off.samples.back().x > 19.5);

  CancelToken token;
  token.cancel();
  Trajectory c = simulate(dem, {{18.0, 10.0}}, {2.0, 10.0, 0.0}, 0.0, {}, {}, {}, &token);
  CHECK(c.status == SimStatus::Cancelled);
  CHECK(c.samples.size() == 2);

  // Already inside the only acceptance circle: one sample, reached.
  Trajectory here = run(dem, {{2.1, 10.0}}, {2.0, 10.0, 0.0});
  CHECK(here.status == SimStatus::Reached);
  CHECK(here.samples.size() == 1);
}

TEST_CASE("sim: validation errors name the field") {
  auto fieldOf = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const Error& e) {
      return e.code() == ErrorCode::InvalidParameter ? e.field() : "wrong code: " + e.field();
    }
    return "no error";
  };
  {
    RoverModel m;
    m.mass = 0;
    CHECK_THROWS_WITH_AS(m.validate(), "mass: must be a finite number > 0", Error);
    m = {};
    m.motorTimeConstant = std::numeric_limits<double>::quiet_NaN();
    CHECK(fieldOf([&] { m.validate(); }) == "motor_time_constant");
    m = {};
    m.trackWidth = -0.2;
    CHECK(fieldOf([&] { m.validate(); }) == "track_width");
    CHECK_NOTHROW(RoverModel{}.validate());
  }
  {
    ControllerParams c;
    c.lookahead = 0;
    CHECK(fieldOf([&] { c.validate(); }) == "lookahead");
    c = {};
    c.acceptanceRadius = -1;
    CHECK(fieldOf([&] { c.validate(); }) == "acceptance_radius");
    c = {};
    c.speedFloor = 1.5;
    CHECK(fieldOf([&] { c.validate(); }) == "speed_floor");
    c = {};
    c.slopeForFloor = 2.0;
    CHECK(fieldOf([&] { c.validate(); }) == "slope_for_floor");
    c = {};
    c.samplePeriod = 0.105;
    CHECK(fieldOf([&] { c.validate(); }) == "sample_period");
    c = {};
    c.headingKi = -1;
    CHECK(fieldOf([&] { c.validate(); }) == "heading_ki");
    c = {};
    c.timeLimit = -5;
    CHECK(fieldOf([&] { c.validate(); }) == "time_limit");
    CHECK_NOTHROW(ControllerParams{}.validate());
  }
  {
    SlipParams s;
    s.correlationTime = 0;
    CHECK(fieldOf([&] { s.validate(); }) == "slip_correlation_time");
    s = {};
    s.gain = -0.1;
    CHECK(fieldOf([&] { s.validate(); }) == "slip_gain");
    CHECK_NOTHROW(SlipParams{}.validate());
  }
  // Cross-field checks and bad inputs, through simulate().
  const terrain::Dem dem = flat20();
  const std::vector<Eigen::Vector2d> wps{{10.0, 10.0}};
  ControllerParams fast;
  fast.nominalSpeed = 0.8;
  CHECK(fieldOf([&] { simulate(dem, wps, {2, 2, 0}, 0, {}, fast, {}); }) == "nominal_speed");
  try {
    simulate(dem, {}, {2, 2, 0}, 0, {}, {}, {});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::InvalidInput);
    CHECK(e.field() == "waypoints");
  }
  try {
    simulate(dem, wps, {-1, 2, 0}, 0, {}, {}, {});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::InvalidInput);
    CHECK(e.field() == "start");
  }
}
