#pragma once
// What a coverage run leaves behind, a stage of the coverage engine
// (core/coverage/coverage_planner.cpp): each rover's track (cells, distance, paper 000 eq. 5
// energy, pitch), the coverage curve, the events a sink asked for, and the metrics at the end.
// Energy and pitch of the flat one-cell moves of a world without heights are worked out once, not
// per move (the trigonometry per move was a tenth of a study's time, .decisions/0001).
#include <array>
#include <cstdint>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/coverage_rover.hpp"
#include "core/coverage/world.hpp"
#include "core/planning/events.hpp"

namespace rover::coverage {

class Plant;
class TeamOccupancy;

// Paper 000 eq. 5 per move: turn and forward energy, with the flat straight and diagonal moves of
// one cell and the five spot turns computed once by the same functions (the same numbers).
class MoveEnergy {
 public:
  MoveEnergy(const EnergyModel& e, double cell);
  double turn(int fromDir, int toDir) const { return turn_[fromDir & 7][toDir & 7]; }
  double forward(double horizontal, double dh) const;
  // atan(|Δh| / horizontal) in degrees: 0 on the flat without the call.
  static double pitchDeg(double horizontal, double dh);

 private:
  EnergyModel e_;
  // Per heading and direction (the five distinct values turnEnergy gives, looked up without
  // turnSteps' two remainders a move).
  std::array<std::array<double, 8>, 8> turn_{};
  double straight_, diagonal_, flatStraight_, flatDiagonal_;
};

// A bump as the incident the result lists and the sink is told (the same note in both).
Incident bumpIncident(const Bump& b, const GridGeometry& g);

class Recorder {
 public:
  Recorder(const World& world, const CoverageParams& params, EventSink* sink,
           const std::vector<StartCell>& starts);

  RoverTrack& track(int rover) { return tracks_[static_cast<std::size_t>(rover)]; }
  // A cell's displayed state changed; kept for the sink's next frame (nothing without a sink).
  void cellChanged(int cell, CellState state, std::uint32_t visits) {
    if (sink_) changes_.push_back({cell, static_cast<std::uint8_t>(state), visits});
  }
  // A move that happened: `horizontal` metres and `dh` metres up on the truth, from heading
  // `fromHeading` into direction `dir`; `revisit` when the cell was visited before.
  void moved(int rover, int to, int fromHeading, int dir, double horizontal, double dh, bool revisit);
  // A spot turn without a move (back onto a circumnavigated line, or towards a bump).
  void turned(int rover, int fromDir, int toDir) { track(rover).energyJ += energy_.turn(fromDir, toDir); }
  void waited(int rover) { ++track(rover).waits; }
  // A bump that is listed (kMaxBumpRecords): told to the sink at once as an incident.
  void bumped(const Bump& b);
  // The curve's point after a step, and the step's events when there is a sink.
  void stepEnded(std::int64_t step, std::int64_t moves, const TeamOccupancy& team, const Plant& plant,
                 const std::vector<CoverageRover>& rovers);
  std::int64_t moves() const { return curve_.empty() ? 0 : curve_.back().moves; }

  // The result: tracks, curve, metrics (the plant adds its own), the team's final view.
  CoverageResult finish(StopReason stop, std::int64_t steps, TeamOccupancy& team, const Plant& plant);

 private:
  void emit(std::int64_t step, const TeamOccupancy& team, const Plant& plant,
            const std::vector<CoverageRover>& rovers);

  const World& world_;
  const GridGeometry& g_;
  const CoverageParams& p_;
  EventSink* sink_;
  MoveEnergy energy_;
  std::vector<RoverTrack> tracks_;
  std::vector<CurvePoint> curve_;
  std::vector<CellUpdate> changes_;
  std::vector<RoverPose> poses_;
};

}  // namespace rover::coverage
