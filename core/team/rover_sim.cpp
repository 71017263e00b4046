#include "core/team/rover_sim.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

namespace {

constexpr double kPi = std::numbers::pi;

bool finite(double v) { return std::isfinite(v); }

void requirePositive(double v, const char* key) {
  if (!finite(v) || !(v > 0)) throwInvalidParameter(key, "must be a finite number > 0");
}
void requireNonNegative(double v, const char* key) {
  if (!finite(v) || !(v >= 0)) throwInvalidParameter(key, "must be a finite number >= 0");
}

// Angle in (−π, π].
double wrapAngle(double a) {
  double w = std::remainder(a, 2 * kPi);
  return w <= -kPi ? w + 2 * kPi : w;
}

// The project's seeded standard normal (core/common/random.hpp).
double normal(Rng& rng) { return normalDraw(rng); }

// PID with derivative on the measurement (no kick when the setpoint jumps at a waypoint switch)
// and anti-windup by conditional integration: the integral only grows when that does not push a
// saturated output further into saturation.
class Pid {
 public:
  Pid(double kp, double ki, double kd) : kp_(kp), ki_(ki), kd_(kd) {}
  double update(double error, double measuredRate, double dt, double lo, double hi) {
    const double candidate = integral_ + error * dt;
    double out = kp_ * error + ki_ * candidate - kd_ * measuredRate;
    if ((out > hi && error > 0) || (out < lo && error < 0))
      out = kp_ * error + ki_ * integral_ - kd_ * measuredRate;
    else
      integral_ = candidate;
    return std::clamp(out, lo, hi);
  }

 private:
  double kp_, ki_, kd_;
  double integral_ = 0;
};

double polylineLength(const Pose& start, const std::vector<Eigen::Vector2d>& waypoints) {
  double len = 0;
  Eigen::Vector2d prev(start.x, start.y);
  for (const auto& w : waypoints) {
    len += (w - prev).norm();
    prev = w;
  }
  return len;
}

}  // namespace

void RoverModel::validate() const {
  requirePositive(length, "length");
  requirePositive(width, "width");
  requirePositive(trackWidth, "track_width");
  requirePositive(mass, "mass");
  requireNonNegative(gravity, "gravity");
  requirePositive(maxWheelSpeed, "max_wheel_speed");
  requirePositive(maxYawRate, "max_yaw_rate");
  requirePositive(motorTimeConstant, "motor_time_constant");
  requirePositive(maxDriveForce, "max_drive_force");
}

void ControllerParams::validate() const {
  requirePositive(nominalSpeed, "nominal_speed");
  requirePositive(lookahead, "lookahead");
  requirePositive(acceptanceRadius, "acceptance_radius");
  requireNonNegative(speedKp, "speed_kp");
  requireNonNegative(speedKi, "speed_ki");
  requireNonNegative(speedKd, "speed_kd");
  if (speedKp == 0 && speedKi == 0)
    throwInvalidParameter("speed_kp", "speed_kp or speed_ki must be > 0, or the rover never moves");
  requirePositive(headingKp, "heading_kp");
  requireNonNegative(headingKi, "heading_ki");
  requireNonNegative(headingKd, "heading_kd");
  if (!finite(slopeForFloor) || !(slopeForFloor > 0) || !(slopeForFloor < kPi / 2))
    throwInvalidParameter("slope_for_floor", "must be in (0, π/2) radians");
  if (!finite(speedFloor) || !(speedFloor > 0) || !(speedFloor <= 1))
    throwInvalidParameter("speed_floor", "must be in (0, 1]");
  requirePositive(step, "step");
  requirePositive(samplePeriod, "sample_period");
  if (step > samplePeriod) throwInvalidParameter("step", "must not exceed sample_period");
  const double ratio = samplePeriod / step;
  if (std::abs(ratio - std::round(ratio)) > 1e-6 * ratio)
    throwInvalidParameter("sample_period", "must be a whole multiple of step");
  requireNonNegative(timeLimit, "time_limit");
}

void SlipParams::validate() const {
  requireNonNegative(gain, "slip_gain");
  requireNonNegative(noise, "slip_noise");
  requirePositive(correlationTime, "slip_correlation_time");
}

Trajectory simulate(const terrain::Dem& dem, const std::vector<Eigen::Vector2d>& waypoints,
                    Pose start, double startTime, const RoverModel& model,
                    const ControllerParams& ctl, const SlipParams& slip,
                    const CancelToken* cancel) {
  model.validate();
  ctl.validate();
  slip.validate();
  if (ctl.nominalSpeed > model.maxWheelSpeed)
    throwInvalidParameter("nominal_speed", "must not exceed max_wheel_speed");
  // Explicit Euler on the motor lag is stable and accurate only well below its time constant.
  if (ctl.step > model.motorTimeConstant / 2)
    throwInvalidParameter("step", "must not exceed motor_time_constant / 2");
  if (!finite(startTime)) throwInvalidParameter("start_time", "must be a finite number");
  if (waypoints.empty()) throw Error(ErrorCode::InvalidInput, "waypoints", "waypoints: none given");
  for (const auto& w : waypoints)
    if (!w.allFinite())
      throw Error(ErrorCode::InvalidInput, "waypoints", "waypoints: every coordinate must be finite");
  std::optional<terrain::SurfacePoint> surf;  // under the rover, kept from the last map check
  if (finite(start.x) && finite(start.y)) surf = terrain::surfaceAt(dem, start.x, start.y);
  if (!finite(start.heading) || !surf)
    throw Error(ErrorCode::InvalidInput, "start", "start: outside the map or next to nodata");

  const int substeps = static_cast<int>(std::lround(ctl.samplePeriod / ctl.step));
  const double dt = ctl.samplePeriod / substeps;
  const double timeLimit = ctl.timeLimit > 0
                               ? ctl.timeLimit
                               : 60.0 + 5.0 * polylineLength(start, waypoints) / ctl.nominalSpeed;
  const long maxTicks = static_cast<long>(std::ceil(timeLimit / ctl.samplePeriod - 1e-9));

  const double halfTrack = model.trackWidth / 2;
  const double maxAccel = 2 * model.maxDriveForce / model.mass;  // per side: F / (m / 2)
  // Turning has priority over driving: the yaw-rate command is capped so one side can still
  // reach it at zero surge.
  const double yawLimit = std::min(model.maxYawRate, model.maxWheelSpeed / halfTrack);

  // State.
  double x = start.x, y = start.y, psi = wrapAngle(start.heading);
  double vL = 0, vR = 0, u = 0, r = 0, uAccel = 0, distance = 0;
  Pid speedPid(ctl.speedKp, ctl.speedKi, ctl.speedKd);
  Pid headingPid(ctl.headingKp, ctl.headingKi, ctl.headingKd);
  Rng rng(slip.seed);
  const double ouDecay = std::exp(-dt / slip.correlationTime);
  const double ouDrive = std::sqrt(1 - ouDecay * ouDecay);
  double xi = slip.enabled ? normal(rng) : 0.0;  // stationary from the start

  Trajectory out;
  out.samplePeriod = ctl.samplePeriod;
  out.samples.reserve(static_cast<std::size_t>(std::min<long>(maxTicks + 1, 1 << 20)));

  auto record = [&](long k) {
    TrajectorySample s;
    s.time = startTime + static_cast<double>(k) * ctl.samplePeriod;
    s.x = x;
    s.y = y;
    s.heading = psi;
    s.speed = u;
    s.distance = distance;
    if (auto sp = terrain::surfaceAt(dem, x, y)) s.z = sp->height;
    if (auto att = terrain::attitudeAt(dem, x, y, psi)) {
      s.roll = att->roll;
      s.pitch = att->pitch;
    }
    out.samples.push_back(s);
  };

  // Waypoint switching: every acceptance circle the rover is inside is passed, in order.
  std::size_t target = 0;
  Eigen::Vector2d prev(start.x, start.y);
  auto advance = [&]() {
    const Eigen::Vector2d p(x, y);
    while (target < waypoints.size() && (waypoints[target] - p).norm() <= ctl.acceptanceRadius) {
      prev = waypoints[target];
      ++target;
    }
    out.waypointsReached = target;
    return target == waypoints.size();
  };

  record(0);
  if (advance()) {
    out.status = SimStatus::Reached;
    return out;
  }

  bool stopping = false;
  for (long k = 1;; ++k) {
    for (int j = 0; j < substeps; ++j) {
      // Sensing at the current pose (the rover knows its attitude and the local slope).
      const auto att = terrain::attitudeAt(dem, x, y, psi);
      const double roll = att ? att->roll : 0.0, pitch = att ? att->pitch : 0.0;

      double leftCmd = 0, rightCmd = 0;
      if (!stopping && advance()) stopping = true;  // last waypoint reached: brake to the tick
      if (!stopping) {
        // Line-of-sight guidance (Breivik 2003, lookahead-based): aim at the point Δ ahead of
        // the rover's projection on the segment prev → target; once that point would pass the
        // waypoint, aim at the waypoint itself (so a missed circle is approached again).
        const Eigen::Vector2d p(x, y), wp = waypoints[target];
        const Eigen::Vector2d seg = wp - prev;
        const double segLen = seg.norm();
        Eigen::Vector2d aim = wp;
        if (segLen > 1e-9) {
          const Eigen::Vector2d t = seg / segLen;
          const double along = (p - prev).dot(t);
          aim = prev + std::clamp(along + ctl.lookahead, 0.0, segLen) * t;
        }
        const Eigen::Vector2d toAim = aim - p;
        const double psiDesired = toAim.norm() > 1e-9 ? std::atan2(toAim.y(), toAim.x()) : psi;
        const double headingError = wrapAngle(psiDesired - psi);

        // Heading PID → yaw-rate command; derivative on the measured yaw rate.
        const double rCmd = headingPid.update(headingError, r, dt, -yawLimit, yawLimit);

        // Desired surge: nominal, reduced on slopes (linear to the floor at slopeForFloor) and in
        // turns (ours, see ControllerParams).
        const double tilt = std::max(std::abs(pitch), std::abs(roll));
        const double slopeFactor =
            1.0 - (1.0 - ctl.speedFloor) * std::min(tilt / ctl.slopeForFloor, 1.0);
        const double turnFactor = ctl.slowInTurns ? std::max(std::cos(headingError), 0.0) : 1.0;
        const double uDesired = ctl.nominalSpeed * slopeFactor * turnFactor;

        // Surge PID → common-mode track command, limited to what the turn leaves of the wheel
        // speed range (so the anti-windup sees the real saturation); derivative on the
        // measured acceleration.
        const double available = std::max(model.maxWheelSpeed - std::abs(rCmd) * halfTrack, 0.0);
        const double uCmd = speedPid.update(uDesired - u, uAccel, dt, -available, available);
        leftCmd = uCmd - rCmd * halfTrack;
        rightCmd = uCmd + rCmd * halfTrack;
      }

      // Skid-steer drive: each side's track speed follows its command with a first-order lag,
      // the drive acceleration bounded by the motor force (2F/m per side), minus gravity along
      // the slope.
      const double gravityAccel = model.gravity * std::sin(pitch);
      auto trackAccel = [&](double cmd, double v) {
        return std::clamp((cmd - v) / model.motorTimeConstant, -maxAccel, maxAccel) - gravityAccel;
      };
      const double uBefore = u;
      vL += trackAccel(leftCmd, vL) * dt;
      vR += trackAccel(rightCmd, vR) * dt;
      u = (vL + vR) / 2;
      r = (vR - vL) / model.trackWidth;
      uAccel = (u - uBefore) / dt;

      // Slip: lateral drift down the cross slope plus a seeded random part, both growing with
      // slope (SlipParams).
      double vLat = 0;
      if (slip.enabled) {
        const double slope = std::atan(std::hypot(surf->dzdx, surf->dzdy));
        xi = ouDecay * xi + ouDrive * normal(rng);
        vLat = std::abs(u) * (-slip.gain * std::sin(roll) + slip.noise * std::sin(slope) * xi);
      }

      // Kinematics in the horizontal plane (midpoint heading); forward motion is along the
      // ground, so its horizontal share is cos(pitch).
      const double psiMid = psi + r * dt / 2;
      const double forward = u * std::cos(pitch);
      x += (forward * std::cos(psiMid) - vLat * std::sin(psiMid)) * dt;
      y += (forward * std::sin(psiMid) + vLat * std::cos(psiMid)) * dt;
      psi = wrapAngle(psi + r * dt);
      distance += std::hypot(u, vLat) * dt;

      surf = terrain::surfaceAt(dem, x, y);
      if (!surf) {
        out.status = SimStatus::LeftMap;  // samples end at the last tick on the map
        return out;
      }
    }
    record(k);
    if (stopping) {
      out.status = SimStatus::Reached;
      return out;
    }
    if (cancel && cancel->cancelled()) {
      out.status = SimStatus::Cancelled;
      return out;
    }
    if (k >= maxTicks) {
      out.status = SimStatus::TimeLimit;
      return out;
    }
  }
}

SampleDegrees inDegrees(const TrajectorySample& s) {
  constexpr double k = 180.0 / kPi;
  return {s.heading * k, s.roll * k, s.pitch * k};
}

double trajectoryLength(const Trajectory& t) {
  return t.samples.empty() ? 0.0 : t.samples.back().distance;
}

double trajectoryDuration(const Trajectory& t) {
  return t.samples.empty() ? 0.0 : t.samples.back().time - t.samples.front().time;
}

AttitudeExceedance attitudeExceedance(const Trajectory& t, double limit) {
  AttitudeExceedance e;
  e.samples = t.samples.size();
  for (const auto& s : t.samples)
    if (std::abs(s.pitch) > limit || std::abs(s.roll) > limit) ++e.count;
  return e;
}

}  // namespace rover::team
