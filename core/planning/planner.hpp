#pragma once
// The planner interface the server and CLI drive (DESIGN.md): planners registered by name, typed
// parameters described as data, an event sink and a cancellation token handed in, a result out.
// Shaped after OMPL's Planner (solve with a termination condition, its status values, PlannerSpecs):
// each planner describes itself (core/planning/planner_specs.hpp), so no caller needs its name.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/common/params.hpp"
#include "core/coverage/world.hpp"
#include "core/terrain/body.hpp"
#include "core/terrain/dem.hpp"
#include "core/planning/events.hpp"
#include "core/planning/keep_out.hpp"
#include "core/planning/plan_result.hpp"
#include "core/planning/planner_specs.hpp"

namespace rover {

struct RoverStart {
  Eigen::Vector2d position{0, 0};  // local frame, metres
  double heading = 0;              // radians counter-clockwise from east
};

// Everything a planner plans on. Each planner reads the part its PlannerSpecs::ground names: a
// coverage grid reads `world` (and `dem` for its start check), a DEM-and-PDM planner `dem` and `pdm`.
struct PlanningProblem {
  coverage::World world;  // the coverage grid: obstacles and optional heights
  std::vector<RoverStart> rovers;
  std::shared_ptr<const terrain::Dem> dem;  // the map at its planning resolution
  std::shared_ptr<const Raster<float>> pdm;  // PDM masses on the DEM's grid; null = none given
  terrain::Body body = terrain::Body::Unknown;  // the map's body, from its CRS (maps/georef.hpp)
  // The operator's keep-out zones in the local frame; every planner respects them
  // (core/planning/keep_out.hpp says where each rule lives).
  KeepOut keepOut;
  // Threads the caller grants this run (a server's worker: 1, so missions in parallel do not
  // oversubscribe the machine; the CLI: all cores). 0 = all cores.
  unsigned threads = 1;
  // A caller that keeps only metrics and curves (a study's thousands of runs): the planner may
  // leave out what only a viewer reads (per-move track points, per-step attitude series).
  bool metricsOnly = false;
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string name() const = 0;
  virtual std::string summary() const = 0;
  virtual std::vector<ParamInfo> params() const = 0;
  // Whether params() declares `key` (OMPL's ParamSet::hasParam).
  bool hasParam(const std::string& key) const;
  // Named parameter sets a form offers ("paper 001", "fast preview"); none by default.
  virtual std::vector<ParamPreset> presets() const { return {}; }
  // What it plans on, where its rovers start, its progress curve, metrics and stages.
  virtual const PlannerSpecs& specs() const = 0;
  // The parameters alone, cross-field rules included (a study checks each point before it runs
  // anything). Throws rover::Error naming the key.
  virtual void checkParams(const ParamSet& params) const = 0;
  // The defaults that come from a map (its cell, its body's gravity), as a form shows them; the
  // planner resolves the same values when they are not given. None by default.
  virtual ParamSet mapDefaults(const GridGeometry& map, terrain::Body body) const {
    (void)map, (void)body;
    return {};
  }
  // How its ground is laid on a map of this geometry; cheap, throws the parameter's Error before
  // anything big is built. By default the map itself at its own resolution.
  virtual MapGround groundOnMap(const GridGeometry& map, const ParamSet& params) const {
    (void)map, (void)params;
    return {specs().ground, 0, {}};
  }
  // The memory of a mission with `rovers` rovers on `ground` laid on `map` (`pdm`: a PDM is given),
  // before anything is built. It may bound `params` so the run cannot outgrow the estimate
  // (coverage: the step budget a request left to the planner). Throws the parameter's Error.
  virtual MemoryEstimate memoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers,
                                        bool pdm, ParamSet& params) const = 0;
  // `rovers` starts on the problem's ground as PlannerSpecs::starts says, every random choice
  // seeded by `seed`; validate says why when no valid placement was found.
  virtual std::vector<RoverStart> defaultStarts(const PlanningProblem& problem, const ParamSet& params,
                                                int rovers, std::uint64_t seed) const = 0;
  // Full validation, so a server can answer 400 before it queues anything. Throws rover::Error.
  virtual void validate(const PlanningProblem& problem, const ParamSet& params) const = 0;
  // The grid of the planner's cellsChanged events (the coverage grid; the team route's search
  // cells), so a viewer can size it before the run starts.
  virtual GridGeometry eventGrid(const PlanningProblem& problem, const ParamSet& params) const {
    (void)params;
    return problem.world.geometry();
  }
  // Runs to completion or cancellation; `sink` and `cancel` may be null.
  virtual PlanResult run(const PlanningProblem& problem, const ParamSet& params, EventSink* sink,
                         const CancelToken* cancel) const = 0;
};

class PlannerRegistry {
 public:
  void add(std::unique_ptr<Planner> planner);
  // Throws NotFound with field "planner" for an unknown name.
  const Planner& get(const std::string& name) const;
  // Null for an unknown name (a stored record of a planner this build no longer has).
  const Planner* find(const std::string& name) const;
  std::vector<std::string> names() const;

 private:
  std::vector<std::unique_ptr<Planner>> planners_;
};

// A registry holding every planner this build provides.
PlannerRegistry makeBuiltinRegistry();

}  // namespace rover
