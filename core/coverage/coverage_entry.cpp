#include "core/planning/rover_range.hpp"
#include "core/coverage/coverage_entry.hpp"

#include <cstdio>

#include "core/common/error.hpp"
#include "core/coverage/coverage_specs.hpp"
#include "core/coverage/recorder.hpp"
#include "core/grid/direction.hpp"
#include "core/planning/mission_check.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/terrain/layers.hpp"

namespace rover::coverage {

std::vector<StartCell> startsToCells(const GridGeometry& g, const std::vector<RoverStart>& rovers) {
  std::vector<StartCell> out;
  for (std::size_t k = 0; k < rovers.size(); ++k) {
    auto cell = localToCell(g, rovers[k].position);
    const std::string field = "rovers[" + std::to_string(k) + "]";
    if (!cell) throw Error(ErrorCode::InvalidInput, field, field + ": start is outside the map");
    if (!std::isfinite(rovers[k].heading))
      throw Error(ErrorCode::InvalidInput, field, field + ": heading must be a finite angle");
    out.push_back({g.index(*cell), radiansToDir(rovers[k].heading)});
  }
  return out;
}

std::vector<RoverStart> cellsToStarts(const GridGeometry& g, const std::vector<StartCell>& starts) {
  std::vector<RoverStart> out;
  for (const auto& s : starts)
    out.push_back({cellToLocal(g, g.cell(s.cell)), dirToRadians(s.heading)});
  return out;
}

PlanResult toPlanResult(const CoverageResult& r, const GridGeometry& g, bool metricsOnly) {
  PlanResult out;
  out.planner = "coverage";
  out.stopReason = r.stop;
  out.cancelled = r.stop == StopReason::Cancelled;
  const CoverageMetrics& m = r.metrics;
  out.metrics = {
      {"coverage", m.coverage, ""},
      {"coverage_reachable", m.coverageReachable, ""},
      {"moves", static_cast<double>(m.moves), "moves"},
      {"makespan", static_cast<double>(m.makespan), "moves"},
      {"steps", static_cast<double>(m.steps), "steps"},
      {"path_length_ratio", m.pathLengthRatio, ""},
      {"makespan_ratio", m.makespanRatio, ""},
      {"distance_m", m.distanceM, "m"},
      {"energy_j", m.energyJ, "J"},
      {"max_pitch_deg", m.maxPitchDeg, "deg"},
      {"revisits", static_cast<double>(m.revisits), "moves"},
      {"cells", static_cast<double>(m.cells), "cells"},
      {"free_cells", static_cast<double>(m.freeCells), "cells"},
      {"visited_cells", static_cast<double>(m.visitedCells), "cells"},
      {"unreachable_cells", static_cast<double>(m.unreachableCells), "cells"},
  };
  if (m.localisation) {
    // Localisation error (dead_reckoning.hpp): `coverage` above is the rover's own (believed) map.
    out.metrics.insert(out.metrics.end(), {
        {"true_coverage", m.trueCoverage, ""},
        {"believed_coverage", m.coverage, ""},
        {"true_visited_cells", static_cast<double>(m.trueVisitedCells), "cells"},
        {"localisation_mae_m", m.maeM, "m"},
        {"localisation_max_error_m", m.maxErrorM, "m"},
        {"localisation_final_error_m", m.finalErrorM, "m"},
        {"map_accuracy", m.mapAccuracy, ""},
        {"mapped_cells", static_cast<double>(m.mappedCells), "cells"},
        {"bumps", static_cast<double>(m.bumps), "moves"},
        {"loop_closures", static_cast<double>(m.loopClosures), ""},
    });
    for (const Bump& b : r.bumps) out.incidents.push_back(bumpIncident(b, g));
    if (m.bumps > 0)
      out.warnings.push_back(std::to_string(m.bumps) + " bump" + (m.bumps == 1 ? "" : "s") +
                             ": moves into obstacles the rovers' maps held free (localisation error)" +
                             (static_cast<std::size_t>(m.bumps) > r.bumps.size()
                                  ? "; the first " + std::to_string(r.bumps.size()) + " are listed"
                                  : ""));
  }
  for (std::size_t k = 0; k < r.rovers.size(); ++k) {
    const RoverTrack& t = r.rovers[k];
    Track track;
    track.rover = static_cast<int>(k);
    if (metricsOnly) {
      // no points: nobody draws them
    } else if (m.localisation) {
      track.points = t.truePoints;
      track.believed = t.believedPoints;
    } else {
      track.points.reserve(t.cells.size());
      for (int c : t.cells) track.points.push_back(cellToLocal(g, g.cell(c)));
    }
    track.metrics = {{"moves", static_cast<double>(t.moves), "moves"},
                     {"waits", static_cast<double>(t.waits), "steps"},
                     {"revisits", static_cast<double>(t.revisits), "moves"},
                     {"distance_m", t.distanceM, "m"},
                     {"energy_j", t.energyJ, "J"},
                     {"max_pitch_deg", t.maxPitchDeg, "deg"}};
    if (m.localisation)
      track.metrics.insert(track.metrics.end(),
                           {{"bumps", static_cast<double>(t.bumps), "moves"},
                            {"loop_closures", static_cast<double>(t.loopClosures), ""},
                            {"localisation_mae_m", t.maeM, "m"}});
    out.tracks.push_back(std::move(track));
  }
  // One point per step of every run (a study's runs included): sized once and written in place,
  // the push_back per point was a twentieth of a coverage study's instructions.
  Series curve{"coverage_vs_moves", "moves", "coverage", {}, {}};
  const std::size_t points = r.curve.size();
  curve.x.resize(points);
  curve.y.resize(points);
  const double freeCells = m.freeCells;
  for (std::size_t k = 0; k < points; ++k) {
    curve.x[k] = static_cast<double>(r.curve[k].moves);
    curve.y[k] = r.curve[k].visited / freeCells;
  }
  out.series.push_back(std::move(curve));
  if (metricsOnly) return out;
  if (m.localisation) {
    Series truth{"true_coverage_vs_moves", "moves", "true_coverage", {}, {}};
    for (const auto& p : r.curve) {
      truth.x.push_back(static_cast<double>(p.moves));
      truth.y.push_back(static_cast<double>(p.trueVisited) / m.freeCells);
    }
    out.series.push_back(std::move(truth));
    for (std::size_t k = 0; k < r.rovers.size(); ++k) {
      Series err{"localisation_error_m_rover_" + std::to_string(k), "move", "error_m", {}, {}};
      const auto& e = r.rovers[k].errorM;
      for (std::size_t i = 0; i < e.size(); ++i) {
        err.x.push_back(static_cast<double>(i + 1));
        err.y.push_back(e[i]);
      }
      out.series.push_back(std::move(err));
    }
  }
  for (std::size_t k = 0; k < r.rovers.size(); ++k) {
    Series pitch{"pitch_deg_rover_" + std::to_string(k), "move", "pitch_deg", {}, {}};
    const auto& pd = r.rovers[k].pitchDeg;
    for (std::size_t i = 0; i < pd.size(); ++i) {
      pitch.x.push_back(static_cast<double>(i + 1));
      pitch.y.push_back(pd[i]);
    }
    out.series.push_back(std::move(pitch));
  }
  return out;
}

// On a DEM the frontier mode is the default (issue 11). Real terrain holds large impassable and
// nodata areas whose inside the myopic rover never senses, so paper 002's stop rule
// (visited >= coverage·(n − O known)) is never met there: the rover covers every reachable cell and
// then wanders until the 20·n step budget (path length ratio 20 on every shipped DEM). Frontier mode
// stops when no reachable unexplored cell is left (SPEC §1, ours). The paper's rule stays one
// parameter away (frontier: false); synthetic worlds keep it as their default.
static bool frontierByDefault(const PlanningProblem& problem, const ParamSet& params) {
  if (auto it = params.find("frontier"); it != params.end()) return std::get<bool>(it->second);
  return problem.dem != nullptr;
}

ParamSet coverageMapDefaults(const GridGeometry& map, terrain::Body body) {
  const CoverageParams defaults;
  ParamSet out;
  out["coverage_cell"] = defaultCoverageCell(map, defaults.cellBudget);
  if (body != terrain::Body::Unknown) out["gravity"] = terrain::bodyGravity(body);
  out["frontier"] = true;  // see frontierByDefault
  return out;
}

namespace {

class CoveragePlanner final : public Planner {
 public:
  std::string name() const override { return "coverage"; }
  std::string summary() const override {
    return "Myopic grid coverage for one rover or a team (Laîné & Yoshida 2019; Santra et al.), "
           "spiral/boustrophedon cost tables, circumnavigation, overlap/Voronoi teams, frontier "
           "mode.";
  }
  std::vector<ParamInfo> params() const override { return coverageParamTable().infos(); }
  std::vector<ParamPreset> presets() const override { return coverageParamTable().presets(); }
  const PlannerSpecs& specs() const override { return coverageSpecs(); }
  void checkParams(const ParamSet& params) const override { (void)parseCoverageParams(params); }
  ParamSet mapDefaults(const GridGeometry& map, terrain::Body body) const override {
    return coverageMapDefaults(map, body);
  }
  MapGround groundOnMap(const GridGeometry& map, const ParamSet& params) const override {
    return coverageGround(map, params);
  }
  MemoryEstimate memoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers, bool pdm,
                                ParamSet& params) const override {
    (void)pdm;  // the coverage planner reads no PDM
    return coverageMemoryEstimate(map, ground, rovers, params);
  }
  std::vector<RoverStart> defaultStarts(const PlanningProblem& problem, const ParamSet& params, int rovers,
                                        std::uint64_t seed) const override {
    return randomValidStarts(*this, problem, params, rovers, seed);
  }
  void validate(const PlanningProblem& problem, const ParamSet& params) const override {
    const CoverageParams p = parseCoverageParams(params);
    validateWorld(problem.world);
    World zoned;  // the grid with the keep-out zones as obstacles, when there are any
    if (!problem.keepOut.empty()) {
      zoned = problem.world;
      addKeepOut(zoned, problem.keepOut);
    }
    // The one start check of every planner (core/planning/mission_check.hpp): against the map
    // at its own resolution when there is one, then the coverage grid.
    terrain::Traversability trav;
    if (problem.dem) checkGridGeometry(problem.dem->geometry(), "map");  // before slopes divide by it
    if (problem.dem) trav = terrain::traversability(*problem.dem, p.traversability());
    planning::MissionGround ground;
    ground.dem = problem.dem.get();
    ground.classes = problem.dem ? &trav.classes : nullptr;
    ground.impassableDeg = p.impassableDeg;
    ground.grid = problem.keepOut.empty() ? &problem.world : &zoned;
    ground.keepOut = &problem.keepOut;
    planning::StartRules rules;
    rules.distinctCells = true;
    planning::checkMissionStarts(ground, problem.rovers, rules);
  }
  PlanResult run(const PlanningProblem& problem, const ParamSet& params, EventSink* sink,
                 const CancelToken* cancel) const override {
    CoverageParams p = parseCoverageParams(params);
    // Body-aware gravity: the map's body unless the user gave one (issue 11).
    const bool bodyGravity = !params.count("gravity") && problem.body != terrain::Body::Unknown;
    if (bodyGravity) p.energy.gravity = terrain::bodyGravity(problem.body);
    p.frontier = frontierByDefault(problem, params);
    p.recordTracks = !problem.metricsOnly;
    auto cells = startsToCells(problem.world.geometry(), problem.rovers);
    // Keep-out zones are obstacles of the ground truth (core/planning/keep_out.hpp): the rovers
    // sense them as they sense rocks, and the coverage counts them out of the free cells.
    const World* world = &problem.world;
    World zoned;
    int keepOutCells = 0;
    if (!problem.keepOut.empty()) {
      zoned = problem.world;
      keepOutCells = addKeepOut(zoned, problem.keepOut);
      world = &zoned;
    }
    const CoverageResult result = runCoverage(*world, cells, p, sink, cancel);
    PlanResult out = toPlanResult(result, problem.world.geometry(), problem.metricsOnly);
    std::vector<double> distances, energies;
    for (const RoverTrack& t : result.rovers) {
      distances.push_back(t.distanceM);
      energies.push_back(t.energyJ);
    }
    for (auto& w : planning::rangeWarnings(p.range, distances, energies)) out.warnings.push_back(std::move(w));
    if (sink) sink->incidents(out.incidents, true);
    out.metrics.push_back({"keep_out_cells", static_cast<double>(keepOutCells), "cells"});
    out.metrics.push_back({"gravity_m_s2", p.energy.gravity, "m/s²"});
    out.metrics.push_back({"coverage_cell_m", problem.world.geometry().cellWidth, "m"});
    out.assumptions.push_back({"body", terrain::bodyName(problem.body)});
    out.assumptions.push_back({"gravity", params.count("gravity") ? "given"
                                          : bodyGravity          ? "the map's body"
                                                                 : "default (Moon)"});
    out.assumptions.push_back({"stop_rule", p.frontier ? (params.count("frontier") ? "frontier (given)"
                                                                                 : "frontier (the default on a DEM)")
                                                       : "paper 002 (coverage of n − known obstacles)"});
    return out;
  }
};

}  // namespace

std::unique_ptr<Planner> makeCoveragePlanner() {
  return std::make_unique<CoveragePlanner>();
}

}  // namespace rover::coverage
