#pragma once
// Every parameter of a team mission (paper 001, SPEC §3) and of the hybrid mission (SPEC §4), one
// struct the stages read their part of. The [keys] are the parameter names (team_params.cpp).
#include <cstdint>

#include "core/planning/keep_out.hpp"
#include "core/team/coordination.hpp"
#include "core/team/route_generator.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

struct TeamMissionParams {
  RouteMethod routeMethod = RouteMethod::LhcGwConv;  // [route]
  RouteParams route;  // targets [targets], warming levels [warming_levels], tie-break [tie_break]
  double footprint = 5.0;        // m, team footprint = search cell, SPEC §3       [footprint_m]
  double sensingDiameter = 1.0;  // m, each rover's sensed disc, SPEC §3       [sensing_diameter_m]
  terrain::TraversabilityParams traversability;  // [high_risk_deg, impassable_deg]
  CoordinationParams coordination;
  // rad; samples with |roll| or |pitch| above it are exceedances (paper 001 §4.3: 15°). Kept apart
  // from the planning limit (coordination.rrt.attitudeLimit) so a margin can be planned in.
  double exceedanceLimit = kDefaultAttitudeLimit;  //                            [exceedance_limit]
  std::uint64_t seed = 1;  // RRT*, slip and the hybrid's coverage                        [seed]
  // Hybrid only (SPEC §4): the footprint is covered on a grid of this cell (the sensing
  // diameter by default) up to this fraction of its free cells, each rover in its own Voronoi
  // region by default so team mates do not cross.
  double hybridCell = 1.0;        // m                                             [hybrid_cell_m]
  double hybridCoverage = 1.0;    // fraction                                    [hybrid_coverage]
  bool hybridVoronoi = true;      //                                             [hybrid_voronoi]
  // The operator's keep-out zones (core/planning/keep_out.hpp), from the problem, not a table
  // parameter; planned paths keep `keepOutMargin` metres from them (ours: the simulated rover
  // cuts corners by up to ~0.3 m, and a try with a sample in a zone's cells is refused).
  KeepOut keepOut;
  double keepOutMargin = 0.5;  // m                                          [keep_out_margin]
  // Timed coordination only (issue 25, sub_teams.hpp): teams larger than this split into
  // ⌈N / subTeamSize⌉ sub-teams, each flying paper 001's formation over its own segment of the
  // route; 0 = one team whatever N. The paper mode always keeps paper 001's single team.
  int subTeamSize = 5;  //                                                        [sub_team_size]

  void validate() const;
};

}  // namespace rover::team
