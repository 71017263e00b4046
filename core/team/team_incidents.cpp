#include "core/team/team_incidents.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

namespace rover::team {

namespace {
constexpr double kDeg = 180.0 / std::numbers::pi;

Incident make(IncidentKind kind, int rover, int other, double time, const Eigen::Vector2d& at, double value,
              std::string note, std::string cause) {
  Incident i;
  i.kind = kind;
  i.rover = rover;
  i.other = other;
  i.time = time;
  i.position = at;
  i.value = value;
  i.note = std::move(note);
  i.cause = std::move(cause);
  return i;
}
}  // namespace

std::optional<Incident> ExceedanceScan::add(const TrajectorySample& s) {
  const double roll = std::abs(s.roll), pitch = std::abs(s.pitch);
  if (std::max(roll, pitch) <= limit_) return finish();
  if (count_ == 0) first_ = s, worst_ = 0;
  ++count_;
  if (roll > worst_) worst_ = roll, worstPitch_ = false;
  if (pitch > worst_) worst_ = pitch, worstPitch_ = true;
  return std::nullopt;
}

std::optional<Incident> ExceedanceScan::finish() {
  if (count_ == 0) return std::nullopt;
  Incident i = episode();
  count_ = 0;
  return i;
}

Incident ExceedanceScan::episode() const {
  char note[160];
  std::snprintf(note, sizeof note, "|%s| reached %.2f° over exceedance_limit %.1f° for %zu samples",
                worstPitch_ ? "pitch" : "roll", worst_ * kDeg, limit_ * kDeg, count_);
  return make(IncidentKind::Exceedance, rover_, -1, first_.time, {first_.x, first_.y}, worst_ * kDeg, note,
              "exceedance_limit");
}

Incident legIncident(const LegRecord& leg, const Eigen::Vector2d& at) {
  return make(leg.status == LegStatus::Short ? IncidentKind::Short : IncidentKind::Skipped, leg.rover, -1, leg.endTime,
              at, static_cast<double>(leg.target), "target " + std::to_string(leg.target) + ": " + leg.note,
              std::string(enumName(leg.reason)));
}

Incident collisionIncident(const Conflict& c, double safetyDistance) {
  char note[160];
  std::snprintf(note, sizeof note, "rovers %d and %d came within %.2f m, under safety_distance %.2f m, for %.1f s",
                c.other + 1, c.rover + 1, c.distance, safetyDistance, c.duration);
  return make(IncidentKind::Collision, c.rover, c.other, c.time, c.position, c.distance, note, "safety_distance");
}

Incident noSlotIncident(int rover, int target, const Eigen::Vector2d& at, double footprint,
                        bool wholeCell) {
  char note[240];
  std::snprintf(note, sizeof note,
                "target %d: no valid ground for the rover's slot within half footprint_m (%.2f m of %.2f m)%s",
                target, footprint / 2, footprint,
                wholeCell ? ", nor any left free in the target's search cell" : "");
  return make(IncidentKind::NoSlot, rover, -1, 0.0, at, static_cast<double>(target), note, "no_ground");
}

}  // namespace rover::team
