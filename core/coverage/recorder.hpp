#pragma once
// What a coverage run leaves behind, a stage of the coverage engine
// (core/coverage/coverage_planner.cpp): each rover's track (cells, distance, paper 000 eq. 5
// energy, pitch), the coverage curve, the events a sink asked for, and the metrics at the end.
// Energy and pitch of the flat one-cell moves of a world without heights are worked out once, not
// per move (the trigonometry per move was a tenth of a study's time, .decisions/0001).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/coverage/coverage_params.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "core/coverage/coverage_rover.hpp"
#include "core/coverage/energy.hpp"
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
  double forward(double horizontal, double dh) const {
    // forwardEnergy(e, h, ±0) is the same number for the same h: look the two grid moves up.
    if (dh == 0 && horizontal == straight_) return flatStraight_;
    if (dh == 0 && horizontal == diagonal_) return flatDiagonal_;
    return forwardEnergy(e_, horizontal, dh);
  }
  // atan(|Δh| / horizontal) in degrees: 0 on the flat without the call.
  static double pitchDeg(double horizontal, double dh) {
    if (dh == 0) return 0.0;  // atan(0) · 180/π
    return std::atan(std::fabs(dh) / horizontal) * 180.0 / std::numbers::pi;
  }

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
  // Inline with stepEnded: the engine calls both every move, and the calls' own cost was a tenth
  // of a move's instructions.
  void moved(int rover, int to, int fromHeading, int dir, double horizontal, double dh, bool revisit) {
    RoverTrack& t = track(rover);
    const double pitchDeg = MoveEnergy::pitchDeg(horizontal, dh);
    t.energyJ += energy_.turn(fromHeading, dir) + energy_.forward(horizontal, dh);
    t.distanceM += horizontal;
    t.maxPitchDeg = std::max(t.maxPitchDeg, pitchDeg);
    if (p_.recordTracks) {
      t.pitchDeg.push_back(static_cast<float>(pitchDeg));
      t.cells.push_back(to);
    }
    ++t.moves;
    t.revisits += revisit;
  }
  // A spot turn without a move (back onto a circumnavigated line, or towards a bump).
  void turned(int rover, int fromDir, int toDir) { track(rover).energyJ += energy_.turn(fromDir, toDir); }
  void waited(int rover) { ++track(rover).waits; }
  // A bump that is listed (kMaxBumpRecords): told to the sink at once as an incident.
  void bumped(const Bump& b);
  // The curve's point after a step (`visited` cells in the rovers' maps, `trueVisited` truly
  // stood in), and the step's events when there is a sink.
  void stepEnded(std::int64_t step, std::int64_t moves, int visited, int trueVisited, const TeamOccupancy& team,
                 const Plant& plant, const std::vector<CoverageRover>& rovers) {
    curve_.push_back({step, moves, visited, trueVisited});
    if (sink_) emit(step, team, plant, rovers);
  }
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
