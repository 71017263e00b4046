#include "core/coverage/coverage_params.hpp"

#include <algorithm>
#include <cmath>

namespace rover::coverage {

MotionCostTable CoverageParams::table() const {
  if (pattern == "boustrophedon") return boustrophedonTable();
  if (pattern == "custom") return tableFromList(costTable, "cost_table");
  return spiralTable();
}

terrain::TraversabilityParams CoverageParams::traversability() const {
  terrain::TraversabilityParams t;
  t.impassableDeg = impassableDeg;
  // High risk does not change a coverage cell; kept below the impassable slope as the layer needs.
  t.highRiskDeg = std::min(t.highRiskDeg, impassableDeg * 2.0 / 3.0);
  return t;
}

namespace {

using P = CoverageParams;

// A real-valued field bound by pointer to member.
void addReal(ParamTable<P>& t, ParamInfo info, double P::*field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return p.*field; },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { p.*field = paramAsReal(i, v); });
}
void addEnergy(ParamTable<P>& t, ParamInfo info, double EnergyModel::*field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return p.energy.*field; },
      [field](P& p, const ParamInfo& i, const ParamValue& v) {
        p.energy.*field = paramAsReal(i, v);
      });
}
void addLocalisation(ParamTable<P>& t, ParamInfo info, double LocalisationModel::*field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return p.localisation.*field; },
      [field](P& p, const ParamInfo& i, const ParamValue& v) {
        p.localisation.*field = paramAsReal(i, v);
      });
}
void addFlag(ParamTable<P>& t, ParamInfo info, bool P::*field) {
  t.add(
      std::move(info), [field](const P& p) -> ParamValue { return p.*field; },
      [field](P& p, const ParamInfo& i, const ParamValue& v) { p.*field = paramAsBool(i.key, v); });
}

ParamTable<P> buildTable() {
  ParamTable<P> t;
  t.group("motion");
  t.add(
      common(choiceParam("mode", {"overlap", "voronoi"},
             "Team strategy (paper 002 §2.3): one shared map, or one Voronoi region per rover.")),
      [](const P& p) -> ParamValue {
        return std::string(p.mode == TeamMode::Overlap ? "overlap" : "voronoi");
      },
      [](P& p, const ParamInfo& i, const ParamValue& v) {
        p.mode = paramAsChoice(i, v) == "overlap" ? TeamMode::Overlap : TeamMode::Voronoi;
      });
  t.add(
      common(choiceParam("pattern", {"spiral", "boustrophedon", "custom"},
             "Motion pattern: the static cost table preset, or custom (then give cost_table).")),
      [](const P& p) -> ParamValue { return p.pattern; },
      [](P& p, const ParamInfo& i, const ParamValue& v) { p.pattern = paramAsChoice(i, v); });
  {
    ParamInfo i;
    i.key = "cost_table";
    i.type = ParamType::RealList;
    i.doc =
        "Custom static costs: 8 relative to the heading (straight, L45, L90, L135, back, R135, "
        "R90, R45), optionally followed by 8 absolute (E, NE, N, NW, W, SW, S, SE).";
    t.add(
        i, [](const P& p) -> ParamValue { return p.costTable; },
        [](P& p, const ParamInfo& i, const ParamValue& v) {
          p.costTable = paramAsRealList(i.key, v);
        });
  }
  addFlag(t,
          common(boolParam("circumnavigate",
               "Follow an obstacle's contour when it blocks the way ahead, "
               "until the original line is regained (paper 002 §2.2).")),
          &P::circumnavigate);
  addFlag(t,
          common(boolParam("frontier",
               "When every neighbour is visited, take the shortest known path to the "
               "nearest unexplored cell; stop when none is reachable (ours).")),
          &P::frontier);
  t.add(
      intParam("sense_radius", 1, 2, "cells",
              "Myopic sensing radius (Chebyshev): 1 = 8 cells, 2 = 24."),
      [](const P& p) -> ParamValue { return std::int64_t{p.senseRadius}; },
      [](P& p, const ParamInfo& i, const ParamValue& v) {
        p.senseRadius = static_cast<int>(paramAsInt(i, v));
      });
  addReal(t,
          common(realParam("coverage", 0.01, 1.0, "",
               "Coverage goal: stop when visited >= goal·(n − known obstacles).")),
          &P::coverage);
  t.group("cost");
  addReal(t,
          common(realParam("alpha", 0.0, 1.0, "",
               "Weight of static + visited cost (paper 000 eq. 3); alpha + beta = 1.")),
          &P::alpha);
  addReal(t, common(realParam("beta", 0.0, 1.0, "", "Weight of the height difference |Δh| (paper 000 eq. 3).")),
          &P::beta);
  addReal(t,
          realParam("mc_visited", 1.1, 1000.0, "",
               "Cost added per previous visit of a cell (paper 000: >= 1.1)."),
          &P::mcVisited);
  t.group("grid");
  t.add(
      intParam("max_steps", 0, 1e9, "steps", "Step budget; 0 = 20 × number of cells."),
      [](const P& p) -> ParamValue { return p.maxSteps; },
      [](P& p, const ParamInfo& i, const ParamValue& v) { p.maxSteps = paramAsInt(i, v); });
  addReal(t,
          common(realParam("coverage_cell", 0.0, 1e7, "m",
                    "Coverage grid cell on a DEM: square cells laid in the map's local frame; 0 = "
                    "from the map (its own cell, or the smallest size that fits cell_budget).")),
          &P::coverageCell);
  t.add(
      intParam("cell_budget", 4, 1e6, "cells",
               "On a DEM, the default coverage_cell is the map's own cell or the smallest that "
               "keeps the grid within this many cells."),
      [](const P& p) -> ParamValue { return p.cellBudget; },
      [](P& p, const ParamInfo& i, const ParamValue& v) { p.cellBudget = paramAsInt(i, v); });
  addReal(t,
          realParam("impassable_deg", 0.1, 89.9, "deg",
                    "On a DEM: a pixel with a slope of this or more to a neighbour is impassable, "
                    "and its coverage cell an obstacle (SPEC §2)."),
          &P::impassableDeg);
  t.group("energy");
  addEnergy(t, realParam("rover_mass", 0.1, 1000.0, "kg", "Rover mass (CLOVER: 7 kg)."),
            &EnergyModel::massKg);
  addEnergy(t,
            common(realParam("gravity", 0.1, 30.0, "m/s²",
                      "Surface gravity (Moon 1.62, Mars 3.71, Earth 9.81); by default the map's "
                      "body's, from its CRS.")),
            &EnergyModel::gravity);
  addEnergy(t, realParam("rolling_resistance", 0.0, 2.0, "", "Rolling resistance coefficient μ."),
            &EnergyModel::rollingResistance);
  addEnergy(t, realParam("drive_efficiency", 0.01, 1.0, "", "Drive-train efficiency η."),
            &EnergyModel::efficiency);
  addEnergy(t, realParam("turn_energy", 0.0, 1000.0, "J/rad", "Energy per radian of spot turn."),
            &EnergyModel::turnJoulesPerRad);
  t.add(realParam("rover_range_m", 0, 1e9, "m",
                  "The farthest one rover may drive in the mission (0 = not stated); a rover past it makes the "
                  "run end with a warning."),
        [](const P& p) -> ParamValue { return p.range.rangeM; },
        [](P& p, const ParamInfo& i, const ParamValue& v) { p.range.rangeM = paramAsReal(i, v); });
  t.add(realParam("rover_energy_j", 0, 1e12, "J",
                  "The energy one rover's battery holds for the mission (0 = not stated); a rover past it makes "
                  "the run end with a warning."),
        [](const P& p) -> ParamValue { return p.range.energyJ; },
        [](P& p, const ParamInfo& i, const ParamValue& v) { p.range.energyJ = paramAsReal(i, v); });
  // Localisation error (issue 15, core/coverage/dead_reckoning.hpp).
  t.group("localisation");
  addLocalisation(t,
                  common(realParam("odometry_noise", 0.0, 50.0, "%",
                            "Odometry drift: std of each move's travelled distance, in % of the "
                            "move; 0 with heading_noise 0 = the rover knows its pose exactly.")),
                  &LocalisationModel::distanceNoisePct);
  addLocalisation(t,
                  common(realParam("heading_noise", 0.0, 45.0, "deg",
                            "Odometry drift: std of the heading error each move adds (it "
                            "accumulates, like the dead-reckoned heading).")),
                  &LocalisationModel::headingNoiseDeg);
  addLocalisation(t,
                  realParam("slip_per_deg", 0.0, 10.0, "%/deg",
                            "Wheel slip: an uphill move falls short by this % of its length per "
                            "degree of pitch (at most 90 %); the odometry does not see it."),
                  &LocalisationModel::slipPctPerDeg);
  t.add(
      boolParam("loop_closure",
                "On a revisit of a cell mapped at least loop_closure_gap moves before, the pose "
                "error shrinks to loop_closure_keep of itself (a stand-in for paper 000's graph "
                "SLAM)."),
      [](const P& p) -> ParamValue { return p.localisation.loopClosure; },
      [](P& p, const ParamInfo& i, const ParamValue& v) {
        p.localisation.loopClosure = paramAsBool(i.key, v);
      });
  addLocalisation(t,
                  realParam("loop_closure_keep", 0.0, 1.0, "",
                            "Fraction of the position and heading error left after a loop closure."),
                  &LocalisationModel::loopClosureKeep);
  t.add(
      intParam("loop_closure_gap", 1, 1e9, "moves",
               "A revisit closes a loop only when the cell was last entered at least this many "
               "moves (of the team) before."),
      [](const P& p) -> ParamValue { return p.localisation.loopClosureGap; },
      [](P& p, const ParamInfo& i, const ParamValue& v) {
        p.localisation.loopClosureGap = paramAsInt(i, v);
      });
  t.add(
      intParam("noise_seed", 0, 9.007199254740992e15, "",
               "Seed of the odometry noise (same seed, same run)."),
      [](const P& p) -> ParamValue { return static_cast<std::int64_t>(p.localisation.seed); },
      [](P& p, const ParamInfo& i, const ParamValue& v) {
        p.localisation.seed = static_cast<std::uint64_t>(paramAsInt(i, v));
      });
  // Presets (the page's form offers them; GET /api/planners lists them).
  t.preset("paper 002",
           "Laîné & Yoshida (paper 002): the spiral cost table without circumnavigation or "
           "frontier, sensing radius 1, mc_visited 1.1, alpha 1 and beta 0 (eq. 1), overlap teams, "
           "95 % coverage goal.",
           {{"pattern", std::string("spiral")}, {"mode", std::string("overlap")},
            {"circumnavigate", false}, {"frontier", false}, {"sense_radius", std::int64_t{1}},
            {"coverage", 0.95}, {"alpha", 1.0}, {"beta", 0.0}, {"mc_visited", 1.1}});
  t.preset("fast preview",
           "A quick look: frontier mode (no wandering for the last cells), 80 % coverage goal on a "
           "grid of at most 10 000 cells.",
           {{"frontier", true}, {"coverage", 0.8}, {"cell_budget", std::int64_t{10000}}});
  return t;
}

}  // namespace

const ParamTable<CoverageParams>& coverageParamTable() {
  static const ParamTable<CoverageParams> table = buildTable();
  return table;
}

void validateCoverageParams(const CoverageParams& p) {
  // Range checks run through the table so hand-filled structs get the same messages.
  ParamSet all = coverageParamTable().toSet(p);
  coverageParamTable().parse(all);
  if (std::fabs(p.alpha + p.beta - 1.0) > 1e-6)
    throwInvalidParameter("beta", "alpha + beta must equal 1 (paper 000 eq. 3)");
  if (p.pattern == "custom") {
    tableFromList(p.costTable, "cost_table");
  } else if (!p.costTable.empty()) {
    throwInvalidParameter("cost_table", "only used with pattern = custom");
  }
}

CoverageParams parseCoverageParams(const ParamSet& values) {
  CoverageParams p = coverageParamTable().parse(values);
  validateCoverageParams(p);
  return p;
}

}  // namespace rover::coverage
