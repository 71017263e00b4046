// The team planners' parameter table: every key, its range and help, bound to its field.
#include <numbers>
#include <string>
#include <type_traits>

#include "core/team/team_entry.hpp"

namespace rover::team {

namespace {

using P = TeamPlannerParams;
constexpr double kDeg = std::numbers::pi / 180.0;

// Binds a key to a field reached through `field` (a generic lambda returning a reference, so the
// same accessor serves the getter on a const struct and the setter).
template <class F>
void addReal(ParamTable<P>& t, ParamInfo info, F field, double scale = 1.0) {
  t.add(
      std::move(info), [field, scale](const P& p) -> ParamValue { return field(p) / scale; },
      [field, scale](P& p, const ParamInfo& i, const ParamValue& v) {
        field(p) = paramAsReal(i, v) * scale;
      });
}
template <class F>
void addInt(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info),
      [field](const P& p) -> ParamValue { return static_cast<std::int64_t>(field(p)); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) {
        field(p) = static_cast<std::remove_reference_t<decltype(field(p))>>(paramAsInt(i, v));
      });
}
template <class F>
void addBool(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return static_cast<bool>(field(p)); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { field(p) = paramAsBool(i.key, v); });
}

// A flag whose parameter says the opposite of the field (parameters default to false).
template <class F>
void addInverted(ParamTable<P>& t, ParamInfo info, F field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return !field(p); },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { field(p) = !paramAsBool(i.key, v); });
}

ParamTable<P> buildTable() {
  ParamTable<P> t;
  // Route (SPEC §3.1).
  t.group("route");
  t.add(common(choiceParam("route", enumNames<RouteMethod>(),
                    "Team route over the PDM: LHC_GW_CONV (paper 001), plain hill climbing without "
                    "global warming, a boustrophedon lawnmower (baselines), or orienteering (ours: the whole PDM, "
                    "the most mass within targets × footprint metres).")),
        [](const P& p) -> ParamValue { return std::string(enumName(p.mission.routeMethod)); },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          p.mission.routeMethod = parseEnum<RouteMethod>(paramAsChoice(i, v)).value_or(RouteMethod::LhcGwConv);
        });
  addInt(t, common(intParam("targets", 1, 10000, "targets", "Route length: search cells visited after the start (paper 001: 64).")),
         [](auto& p) -> auto& { return p.mission.route.targets; });
  addInt(t, common(intParam("warming_levels", 0, 1000, "", "Global-warming levels l of eq. 8 (C = p_max / l); 0 = plain hill climb.")),
         [](auto& p) -> auto& { return p.mission.route.warmingLevels; });
  addInverted(t, boolParam("plain_tie_break", "Break hill-climb ties by the fixed neighbour order only, without the 3×3 box blur of eq. 6–7."),
              [](auto& p) -> auto& { return p.mission.route.convolutionTieBreak; });
  addReal(t, common(realParam("footprint_m", 0.25, 1000, "m", "Team footprint: the side of a search cell (paper 001: 5 m).")),
          [](auto& p) -> auto& { return p.mission.footprint; });
  addReal(t, realParam("sensing_diameter_m", 0.01, 100, "m", "Diameter of the disc each rover senses (paper 001: 1 m)."),
          [](auto& p) -> auto& { return p.mission.sensingDiameter; });
  addReal(t, realParam("high_risk_deg", 0.1, 90, "deg", "Traversability: slope from which a cell is high risk."),
          [](auto& p) -> auto& { return p.mission.traversability.highRiskDeg; });
  addReal(t, realParam("impassable_deg", 0.1, 90, "deg", "Traversability: slope from which a cell is impassable (never a target, never entered)."),
          [](auto& p) -> auto& { return p.mission.traversability.impassableDeg; });
  addReal(t, realParam("keep_out_margin", 0, 10, "m", "Planned paths keep this far (along x and y) from the mission's keep-out zones; no sample ever enters a zone's cells."),
          [](auto& p) -> auto& { return p.mission.keepOutMargin; });
  // RRT* and eq. 9 (SPEC §3.2).
  t.group("RRT*");
  addReal(t, common(realParam("range", 0.05, 100, "m", "RRT* range: the longest edge (paper 001: 1 m).")),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.range; });
  addInt(t, common(intParam("max_vertices", 2, 1000000, "", "RRT* grows each tree to this many vertices (paper 001: 1250).")),
         [](auto& p) -> auto& { return p.mission.coordination.rrt.maxVertices; });
  addReal(t, realParam("clearance", 0.01, 1000, "m", "Search bounds: the box of start and goal grown by this (paper 001: 2 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.clearance; });
  addReal(t, common(realParam("attitude_limit", 0.1, 90, "deg", "Roll/pitch limit of a valid RRT* edge (ours 14°, paper 001: 15°). Simulated tries are checked against attitude_check, exceedances counted against exceedance_limit: raise them with it.")),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.attitudeLimit; }, kDeg);
  addReal(t, realParam("goal_bias", 0, 1, "", "RRT* probability of sampling the goal."),
          [](auto& p) -> auto& { return p.mission.coordination.rrt.goalBias; });
  addInt(t, intParam("max_iterations", 1, 10000000, "", "Safety cap on RRT* iterations per tree."),
         [](auto& p) -> auto& { return p.mission.coordination.rrt.maxIterations; });
  t.add(choiceParam("edge_evaluation", enumNames<EdgeEvaluation>(),
                    "How eq. 9 reads an edge's roll and pitch: sampled (paper 001: the largest over samples "
                    "a quarter cell apart), patch (ours: the exact largest over the edge on the bilinear "
                    "surface, from the two ends of its piece in each patch; about half the cost), or auto "
                    "(patch in the timed coordination, sampled in the paper's)."),
        [](const P& p) -> ParamValue { return std::string(enumName(p.mission.coordination.rrt.evaluation)); },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          p.mission.coordination.rrt.evaluation =
              parseEnum<EdgeEvaluation>(paramAsChoice(i, v)).value_or(EdgeEvaluation::Auto);
        });
  addReal(t, realParam("w_r", 0, 1000, "", "Eq. 9 weight of the edge length (0.1)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wR; });
  addReal(t, realParam("w_phi", 0, 1000, "", "Eq. 9 weight of roll (0.4)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wPhi; });
  addReal(t, realParam("w_theta", 0, 1000, "", "Eq. 9 weight of pitch (0.4)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wTheta; });
  addReal(t, realParam("w_psi", 0, 1000, "", "Eq. 9 weight of the heading change (0.1)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.wPsi; });
  addReal(t, realParam("n_r", 0.001, 1000, "m", "Eq. 9 normaliser of the edge length (1 m)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nR; });
  addReal(t, realParam("n_phi", 0.1, 180, "deg", "Eq. 9 normaliser of roll (15°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nPhi; }, kDeg);
  addReal(t, realParam("n_theta", 0.1, 180, "deg", "Eq. 9 normaliser of pitch (15°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nTheta; }, kDeg);
  addReal(t, realParam("n_psi", 0.1, 180, "deg", "Eq. 9 normaliser of the heading change (60°)."),
          [](auto& p) -> auto& { return p.mission.coordination.weights.nPsi; }, kDeg);
  // Coordination (SPEC §3.4).
  t.group("coordination");
  t.add(common(choiceParam("coordination", enumNames<CoordinationMode>(),
                    "timed (ours): RRT* in a corridor round a guide path on the whole map, conflicts "
                    "resolved by starting later (checked at 10 Hz), re-planning only as a fallback; "
                    "paper: paper 001's boxed RRT* and seed re-planning.")),
        [](const P& p) -> ParamValue {
          return std::string(enumName(p.mission.coordination.mode));
        },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          p.mission.coordination.mode =
              parseEnum<CoordinationMode>(paramAsChoice(i, v)).value_or(CoordinationMode::Timed);
        });
  addReal(t, realParam("corridor_radius", 0.5, 100, "m", "timed: RRT* samples within this distance of the leg's guide path."),
          [](auto& p) -> auto& { return p.mission.coordination.corridorRadius; });
  addReal(t, realParam("delay_step", 0.1, 3600, "s", "timed: delays tried before a re-plan are multiples of this, up to max_waits × wait_step."),
          [](auto& p) -> auto& { return p.mission.coordination.delayStep; });
  addReal(t, common(realParam("safety_distance", 0, 100, "m", "Two rovers closer than this collide (SPEC §3.4: 1 m).")),
          [](auto& p) -> auto& { return p.mission.coordination.safetyDistance; });
  addInt(t, common(intParam("max_replans", 0, 1000, "", "Re-plans with a new seed before a rover waits (SPEC §3.4: 20).")),
         [](auto& p) -> auto& { return p.mission.coordination.maxReplans; });
  addReal(t, realParam("wait_step", 0.1, 3600, "s", "Each wait holds the rover this much longer before it tries again."),
          [](auto& p) -> auto& { return p.mission.coordination.waitStep; });
  addInt(t, intParam("max_waits", 0, 1000, "", "Waits before the rover skips the target."),
         [](auto& p) -> auto& { return p.mission.coordination.maxWaits; });
  addReal(t, realParam("keep_out_radius", 0, 100, "m", "A re-plan keeps out of this radius around where the other rover was at each earlier conflict."),
          [](auto& p) -> auto& { return p.mission.coordination.keepOutRadius; });
  addReal(t, realParam("dwell_check", 0, 3600, "s", "Each leg is also checked with the rover standing at its end this long."),
          [](auto& p) -> auto& { return p.mission.coordination.dwellCheck; });
  addReal(t, realParam("attitude_check", 0, 90, "deg", "A simulated try tilting past this is planned again, like a conflict (0 = off)."),
          [](auto& p) -> auto& { return p.mission.coordination.attitudeCheck; }, kDeg);
  addInt(t, intParam("sub_team_size", 0, 64, "rovers", "timed: a team of more rovers splits into ⌈rovers / sub_team_size⌉ sub-teams (sizes as equal as possible, neighbouring starts together), each flying paper 001's formation over its own contiguous segment of the route, all in one traffic table; 0 = one team. The paper coordination always flies one team."),
         [](auto& p) -> auto& { return p.mission.subTeamSize; });
  addInt(t, intParam("max_pieces", 1, 100, "", "RRT* calls chained in one leg when a tree ends short of its goal."),
         [](auto& p) -> auto& { return p.mission.coordination.maxPieces; });
  // The rover and its controller (SPEC §3.3).
  t.group("rover");
  addReal(t, common(realParam("nominal_speed", 0.01, 0.5, "m/s", "Desired surge speed on flat ground (≈0.3 m/s).")),
          [](auto& p) -> auto& { return p.mission.coordination.controller.nominalSpeed; });
  addReal(t, realParam("rover_range_m", 0, 1e9, "m", "The farthest one rover may drive in the mission (0 = not stated); a rover past it makes the run end with a warning."),
          [](auto& p) -> auto& { return p.range.rangeM; });
  addReal(t, realParam("rover_energy_j", 0, 1e12, "J", "The driving energy one rover's battery holds for the mission (0 = not stated); a rover past it makes the run end with a warning."),
          [](auto& p) -> auto& { return p.range.energyJ; });
  addReal(t, realParam("lookahead", 0.05, 100, "m", "Line-of-sight guidance lookahead distance."),
          [](auto& p) -> auto& { return p.mission.coordination.controller.lookahead; });
  addReal(t, realParam("acceptance_radius", 0.01, 10, "m", "A waypoint counts as reached inside this radius."),
          [](auto& p) -> auto& { return p.mission.coordination.controller.acceptanceRadius; });
  t.group("simulation");
  addBool(t, common(boolParam("slip", "Simulate slip: a seeded lateral drift growing with slope (paper 001's cause of exceedances).")),
          [](auto& p) -> auto& { return p.mission.coordination.slip.enabled; });
  addReal(t, realParam("slip_gain", 0, 10, "", "Slip: lateral drift down the cross slope per unit sin(roll)."),
          [](auto& p) -> auto& { return p.mission.coordination.slip.gain; });
  addReal(t, realParam("slip_noise", 0, 10, "", "Slip: std of the random drift per unit sin(slope)."),
          [](auto& p) -> auto& { return p.mission.coordination.slip.noise; });
  addReal(t, common(realParam("exceedance_limit", 0.1, 90, "deg", "Samples with |roll| or |pitch| above this count as exceedances (paper 001: 15°).")),
          [](auto& p) -> auto& { return p.mission.exceedanceLimit; }, kDeg);
  addInt(t, common(intParam("seed", 0, 9.0e18, "", "Seed of every RRT* tree, the slip noise and the coverage runs.")),
         [](auto& p) -> auto& { return p.mission.seed; });
  addReal(t, realParam("pose_interval", 0.1, 600, "s", "Mission time between two pose events of the replay to a viewer."),
          [](auto& p) -> auto& { return p.poseInterval; });
  // Hybrid (SPEC §4).
  t.group("hybrid");
  addReal(t, realParam("hybrid_cell_m", 0.05, 1000, "m", "Hybrid: coverage grid cell inside each footprint (the sensing diameter)."),
          [](auto& p) -> auto& { return p.mission.hybridCell; });
  addReal(t, common(realParam("hybrid_coverage", 0.01, 1, "", "Hybrid: fraction of a footprint's free cells to cover.")),
          [](auto& p) -> auto& { return p.mission.hybridCoverage; });
  addInverted(t, boolParam("hybrid_overlap", "Hybrid: all rovers cover the whole footprint (overlap) instead of one Voronoi region each."),
              [](auto& p) -> auto& { return p.mission.hybridVoronoi; });
  // Presets (the page's form offers them; GET /api/planners lists them).
  t.preset("paper 001",
           "Swinton et al. (paper 001) as SPEC §3 condenses it: LHC_GW_CONV over 64 targets with 20 "
           "warming levels, 5 m footprint, 1 m sensing, boxed RRT* of 1250 vertices (1 m range, 2 m "
           "clearance, eq. 9 weights 0.1/0.4/0.4/0.1 over 1 m/15°/15°/60°), seed re-planning (20) at "
           "1 m safety distance, 0.3 m/s, slip on, 15° limits.",
           {{"route", std::string("lhc_gw_conv")}, {"targets", std::int64_t{64}},
            {"warming_levels", std::int64_t{20}}, {"plain_tie_break", false},
            {"footprint_m", 5.0}, {"sensing_diameter_m", 1.0},
            {"high_risk_deg", 10.0}, {"impassable_deg", 15.0},
            {"range", 1.0}, {"max_vertices", std::int64_t{1250}}, {"clearance", 2.0},
            {"attitude_limit", 15.0}, {"edge_evaluation", std::string("sampled")}, {"w_r", 0.1}, {"w_phi", 0.4}, {"w_theta", 0.4}, {"w_psi", 0.1},
            {"n_r", 1.0}, {"n_phi", 15.0}, {"n_theta", 15.0}, {"n_psi", 60.0},
            {"coordination", std::string("paper")}, {"safety_distance", 1.0},
            {"max_replans", std::int64_t{20}}, {"nominal_speed", 0.3}, {"slip", true},
            {"exceedance_limit", 15.0}});
  t.preset("fast preview",
           "A quick look before the real run: 16 targets, 5 warming levels, RRT* trees of 300 "
           "vertices, 5 re-plans; the rest as the defaults.",
           {{"targets", std::int64_t{16}}, {"warming_levels", std::int64_t{5}},
            {"max_vertices", std::int64_t{300}}, {"max_replans", std::int64_t{5}}});
  return t;
}

}  // namespace

const ParamTable<TeamPlannerParams>& teamParamTable() {
  static const ParamTable<TeamPlannerParams> table = buildTable();
  return table;
}

TeamPlannerParams parseTeamParams(const ParamSet& values) {
  TeamPlannerParams p = teamParamTable().parse(values);
  p.mission.validate();
  return p;
}

}  // namespace rover::team
