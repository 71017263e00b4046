#pragma once
// Rover simulation (paper 001 §2.3, SPEC §3.3): a skid-steered micro-rover follows waypoints with
// line-of-sight guidance (Breivik 2003) and two PID loops, surge speed and heading, on a DEM. The
// pose, roll and pitch are sampled at 10 Hz for the coordination checks (SPEC §3.4) and the
// metrics (SPEC §3.5). Optional slip — a random lateral drift that grows with slope — is the cause
// the paper gives for its few roll/pitch limit exceedances (§4.3).
//
// Units: metres, seconds, radians everywhere; headings counter-clockwise from east (as
// terrain::attitudeAt). Degrees only through inDegrees() at the edges.
//
// Every default below is ours where the paper is silent (it gives the rover's size, the 10 Hz
// sampling and, through 653.68 m in 2295 s, an average speed of ≈0.285 m/s); validate() throws
// InvalidParameter naming the field by its snake_case parameter key (given in brackets).
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/common/enum_names.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

// 15° in radians: the nominal roll/pitch limit (paper 001 §3.4, §4.3).
inline constexpr double kDefaultAttitudeLimit = 15.0 * std::numbers::pi / 180.0;

// A planar pose in the local frame (SPEC §0).
struct Pose {
  double x = 0;        // m, east
  double y = 0;        // m, north
  double heading = 0;  // rad, counter-clockwise from east
};

// The vehicle: paper 001's RBR micro-rover (§2.1) with a first-order motor model per track side.
// Each comment gives the unit, then the parameter key [in brackets] that validate() names.
struct RoverModel {
  double length = 0.271;           // m, paper 001 §2.1 [length]
  double width = 0.251;            // m, paper 001 §2.1 [width]
  double trackWidth = 0.251;       // m, effective left–right track spacing; ours: the chassis
                                   //   width [track_width]
  double mass = 1.5;               // kg; ours, the paper gives none [mass]
  double gravity = 3.71;           // m/s², Mars [gravity]
  double maxWheelSpeed = 0.5;      // m/s, saturation of each side's speed command [max_wheel_speed]
  double maxYawRate = 1.0;         // rad/s, limit on the commanded turn rate [max_yaw_rate]
  double motorTimeConstant = 0.1;  // s, first-order lag of each side's track speed
                                   //   [motor_time_constant]
  double maxDriveForce = 2.0;      // N per side; bounds the drive acceleration to 2F/m
                                   //   [max_drive_force]

  void validate() const;
};

// Guidance, control and integration settings.
struct ControllerParams {
  double nominalSpeed = 0.3;       // m/s, desired surge speed on flat ground, SPEC §3.3
                                   //   [nominal_speed]
  double lookahead = 1.0;          // m, Breivik's lookahead distance Δ [lookahead]
  double acceptanceRadius = 0.25;  // m, switch to the next waypoint inside it [acceptance_radius]
  double speedKp = 2.0;            // (m/s)/(m/s), surge PID [speed_kp]
  double speedKi = 5.0;            // 1/s, surge PID [speed_ki]
  double speedKd = 0.0;            // s, surge PID, on the measured acceleration [speed_kd]
  double headingKp = 2.0;          // (rad/s)/rad, heading PID [heading_kp]
  // 1/s², heading PID [heading_ki]. 0 by default: the yaw plant is an integrator with no steady
  // disturbance in this model, so an integral only adds a slow tail (measured: Ki = 0.1 leaves
  // ~1 mrad of heading bias decaying over ~20 s after a turn). Anti-windup is in place for users
  // who set it.
  double headingKi = 0.0;
  double headingKd = 0.2;          // s, heading PID, on the measured yaw rate [heading_kd]
  // Slope-aware speed (ours): the desired speed falls linearly with max(|pitch|, |roll|) from the
  // nominal at 0 to speedFloor × nominal at slopeForFloor and beyond.
  double slopeForFloor = kDefaultAttitudeLimit;  // rad, 15° [slope_for_floor]
  double speedFloor = 0.5;         // fraction of nominal, in (0, 1] [speed_floor]
  // Slow down in turns (ours): desired speed × max(cos e_ψ, 0), so a sharp corner is taken almost
  // on the spot instead of in a wide arc [slow_in_turns].
  bool slowInTurns = true;
  double step = 0.01;              // s, fixed integration step [step]
  double samplePeriod = 0.1;       // s, output sampling, 10 Hz (paper 001 §4.3); a whole
                                   //   multiple of step [sample_period]
  // s of simulated time after startTime; 0 = automatic: 60 s + 5 × the waypoint polyline length
  // (from the start) / nominalSpeed [time_limit].
  double timeLimit = 0.0;

  void validate() const;
};

// Slip (ours; paper 001 §4.3 names it as the cause of its exceedances). The lateral drift velocity,
// positive to the rover's left, is
//   v_lat = |u| · (−gain · sin(roll) + noise · sin(slope) · ξ(t)),
// i.e. a bias down the cross slope plus a random part, both growing with the terrain slope; ξ is a
// unit-variance Ornstein–Uhlenbeck process with the given correlation time, seeded.
struct SlipParams {
  bool enabled = false;            // [slip]
  double gain = 0.5;               // lateral slip ratio per unit sin(roll) [slip_gain]
  double noise = 0.5;              // std of the random slip ratio per unit sin(slope) [slip_noise]
  double correlationTime = 2.0;    // s, of ξ [slip_correlation_time]
  std::uint64_t seed = 0;          // [slip_seed]

  void validate() const;
};

// How a simulation ended: expected outcomes, not errors.
enum class SimStatus {
  Reached,    // the last waypoint's acceptance circle was entered
  TimeLimit,  // ControllerParams::timeLimit ran out first
  LeftMap,    // the rover left the grid or drove next to nodata; samples end before it did
  Cancelled,  // the CancelToken was set
};

// One 10 Hz sample. Angles in radians.
struct TrajectorySample {
  double time = 0;      // s (startTime + k × samplePeriod)
  double x = 0;         // m, east
  double y = 0;         // m, north
  double z = 0;         // m, terrain height under the rover
  double heading = 0;   // rad, counter-clockwise from east, in (−π, π]
  double speed = 0;     // m/s, surge speed along the ground
  double roll = 0;      // rad, positive = ground rising to the left (terrain::attitudeAt)
  double pitch = 0;     // rad, positive = nose up
  double distance = 0;  // m, path length over the ground since the start (slip included)
};

struct Trajectory {
  std::vector<TrajectorySample> samples;  // at startTime + k × samplePeriod, k = 0, 1, …
  SimStatus status = SimStatus::Reached;
  std::size_t waypointsReached = 0;       // acceptance circles entered, in order
  double samplePeriod = 0.1;              // s
};

// Follows `waypoints` from `start` (at rest). Throws InvalidParameter for bad parameters and
// InvalidInput for an empty or non-finite waypoint list or a start off the map; everything else
// is a status. Deterministic: the same inputs and slip seed give the same samples.
Trajectory simulate(const terrain::Dem& dem, const std::vector<Eigen::Vector2d>& waypoints,
                    Pose start, double startTime, const RoverModel& model,
                    const ControllerParams& controller, const SlipParams& slip,
                    const CancelToken* cancel = nullptr);

// ---- helpers on trajectories ----------------------------------------------------------------

// Angles of a sample in degrees, for the edges (JSON, CSV, UI).
struct SampleDegrees {
  double heading = 0;
  double roll = 0;
  double pitch = 0;
};
SampleDegrees inDegrees(const TrajectorySample& s);

// Path length over the ground (the last sample's distance), m; 0 when empty.
double trajectoryLength(const Trajectory& t);
// Last sample time − first sample time, s; 0 when empty.
double trajectoryDuration(const Trajectory& t);

// Samples with |pitch| > limit or |roll| > limit (paper 001 §4.3: 25 of 942,321).
struct AttitudeExceedance {
  std::size_t count = 0;
  std::size_t samples = 0;
  double fraction() const { return samples ? static_cast<double>(count) / samples : 0.0; }
};
AttitudeExceedance attitudeExceedance(const Trajectory& t, double limit = kDefaultAttitudeLimit);

// Separation between rovers: separation.hpp (one routine for the coordinator and the metrics).

}  // namespace rover::team

// The names of the values above (enum_names.hpp).
namespace rover {
template <>
struct EnumNames<team::SimStatus> {
  static constexpr std::array<EnumName<team::SimStatus>, 4> table{{
      {team::SimStatus::Reached, "reached"},
      {team::SimStatus::TimeLimit, "time_limit"},
      {team::SimStatus::LeftMap, "left_map"},
      {team::SimStatus::Cancelled, "cancelled"},
  }};
};
}  // namespace rover
