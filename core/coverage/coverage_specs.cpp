#include "core/coverage/coverage_specs.hpp"

#include <cmath>

#include "core/common/error.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/coverage_memory.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/terrain_world.hpp"

namespace rover::coverage {

const PlannerSpecs& coverageSpecs() {
  static const PlannerSpecs specs = [] {
    PlannerSpecs s;
    s.ground = Ground::CoverageGrid;
    s.starts = StartPlacement::RandomCells;
    s.progress = ProgressMeasure::Coverage;
    s.progressSeries = "coverage_vs_moves";
    s.metrics = {
        {"coverage", "", "Visited free cells over free cells (the rovers' own map under localisation error)."},
        {"coverage_reachable", "", "Visited cells over the free cells reachable from the starts."},
        {"moves", "moves", "Moves of the whole team."},
        {"makespan", "moves", "Moves of the rover that moved most."},
        {"steps", "steps", "Steps until the stop (each rover moves at most once a step)."},
        {"path_length_ratio", "", "Moves over the grid's cells n (paper 002 eq. 2, summed over the team)."},
        {"makespan_ratio", "", "Makespan over the grid's cells n."},
        {"distance_m", "m", "Distance driven by the team."},
        {"energy_j", "J", "Energy of the team's moves."},
        {"max_pitch_deg", "deg", "Steepest pitch of a move."},
        {"revisits", "moves", "Moves into a cell already visited."},
        {"cells", "cells", "Cells of the grid."},
        {"free_cells", "cells", "Cells that are not obstacles."},
        {"visited_cells", "cells", "Free cells visited."},
        {"unreachable_cells", "cells", "Free cells no start can reach."},
        {"true_coverage", "", "Under localisation error: the share of free cells truly visited."},
        {"believed_coverage", "", "Under localisation error: coverage of the rovers' own map."},
        {"true_visited_cells", "cells", "Under localisation error: cells truly visited."},
        {"localisation_mae_m", "m", "Under localisation error: mean position error over every move."},
        {"localisation_max_error_m", "m", "Under localisation error: largest position error."},
        {"localisation_final_error_m", "m", "Under localisation error: mean over rovers of the last position error."},
        {"map_accuracy", "", "Under localisation error: mapped cells whose obstacle/free state is true, over mapped cells."},
        {"mapped_cells", "cells", "Under localisation error: cells in the rovers' map."},
        {"bumps", "moves", "Under localisation error: moves into obstacles the map held free."},
        {"loop_closures", "", "Under localisation error: loop closures of the rovers."},
        {"keep_out_cells", "cells", "Cells closed by keep-out zones."},
        {"gravity_m_s2", "m/s²", "Gravity of the energy model."},
        {"coverage_cell_m", "m", "Side of the coverage grid's square cell."},
    };
    s.stages = {
        {"grid", "The map resampled to the coverage cell; slopes past the limit and nodata are obstacles."},
        {"sense", "Each rover senses the cells around it into its map (myopic, SPEC §1)."},
        {"move", "Each rover takes the cheapest move of its cost table, circumnavigating obstacles "
                 "and heading for the nearest unvisited cell when none is next to it."},
        {"stop", "At the coverage goal, when no reachable unexplored cell is left (frontier mode), or "
                 "at the step budget."},
    };
    return s;
  }();
  return specs;
}

MapGround coverageGround(const GridGeometry& map, const ParamSet& params) {
  const CoverageParams p = parseCoverageParams(params);
  MapGround g;
  g.kind = Ground::CoverageGrid;
  g.cell = resolveCoverageCell(map, p.coverageCell, p.cellBudget);
  g.traversal = p.traversability();
  return g;
}

MemoryEstimate coverageMemoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers,
                                      ParamSet& params) {
  const CoverageParams p = parseCoverageParams(params);
  const double cell = ground.cell;
  const double cells = std::ceil(map.heightMetres() / cell - 1e-9) * std::ceil(map.widthMetres() / cell - 1e-9);
  // The steps bound the moves, so the estimate covers the mission however long it runs.
  const StepBudget steps = stepBudget(params, p.maxSteps, static_cast<std::int64_t>(cells), rovers);
  return missionMemory(static_cast<std::int64_t>(cells), cell, rovers, p.mode == TeamMode::Voronoi, steps,
                       p.localisation.active());
}

std::vector<RoverStart> randomValidStarts(const Planner& planner, const PlanningProblem& problem,
                                          const ParamSet& params, int rovers, std::uint64_t seed) {
  PlanningProblem trial = problem;
  for (std::uint64_t k = 0;; ++k) {
    trial.rovers = cellsToStarts(problem.world.geometry(), randomStarts(problem.world, rovers, seed + k));
    try {
      planner.validate(trial, params);
      return trial.rovers;
    } catch (const Error& e) {
      if (k >= 20 || e.field().rfind("rovers", 0) != 0) return trial.rovers;  // validate says why
    }
  }
}

}  // namespace rover::coverage
