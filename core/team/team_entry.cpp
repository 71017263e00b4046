#include "core/team/team_entry.hpp"

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>

#include "core/common/error.hpp"
#include "core/planning/mission_check.hpp"
#include "core/team/team_memory.hpp"
#include "core/team/team_replay.hpp"
#include "core/team/team_specs.hpp"
#include "core/terrain/body.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::team {

namespace {

class TeamPlanner final : public Planner {
 public:
  explicit TeamPlanner(bool hybrid) : hybrid_(hybrid) {}
  std::string name() const override { return hybrid_ ? "hybrid" : "team-search"; }
  std::string summary() const override {
    return hybrid_ ? "Hybrid team mission (SPEC §4): the LHC_GW_CONV route picks the footprints, "
                     "the rovers cover each with the myopic DEM-aware planner; RRT* between "
                     "footprints, simulation and prioritised coordination as team-search."
                   : "Team search (Swinton et al.): LHC_GW_CONV team route over the PDM, RRT* "
                     "with the eq. 9 terrain cost per rover and segment, rover simulation at "
                     "10 Hz, prioritised multi-rover coordination.";
  }
  std::vector<ParamInfo> params() const override { return teamParamTable().infos(); }
  std::vector<ParamPreset> presets() const override { return teamParamTable().presets(); }
  const PlannerSpecs& specs() const override { return teamSpecs(hybrid_); }
  void checkParams(const ParamSet& params) const override { (void)parseTeamParams(params); }
  MemoryEstimate memoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers, bool pdm,
                                ParamSet& params) const override {
    (void)ground;  // the map itself
    return missionMemory(map.cellCount(), rovers, pdm, params, hybrid_);
  }
  std::vector<RoverStart> defaultStarts(const PlanningProblem& problem, const ParamSet& params, int rovers,
                                        std::uint64_t seed) const override {
    (void)seed;  // the formation is the same for every seed
    if (!problem.dem) throw Error(ErrorCode::InvalidInput, "map", "the team planners need a DEM");
    return formationStarts(*problem.dem, params, rovers);
  }

  void validate(const PlanningProblem& problem, const ParamSet& params) const override {
    const TeamPlannerParams p = parseTeamParams(params);
    if (!problem.dem || problem.dem->geometry().cellCount() == 0)
      throw Error(ErrorCode::InvalidInput, "map", "the team planners need a DEM");
    const GridGeometry& g = problem.dem->geometry();
    checkGridGeometry(g, "map");  // before the cell size is compared or used
    if (problem.pdm && (problem.pdm->geometry.rows != g.rows || problem.pdm->geometry.cols != g.cols))
      throw Error(ErrorCode::InvalidInput, "pdm", "the PDM must have the DEM's rows and columns");
    planning::checkRoverCount(problem.rovers.size());
    if (p.mission.footprint < std::max(g.cellWidth, g.cellHeight))
      throwInvalidParameter("footprint_m", "must be at least the map cell size");
    const auto classes = classesFor(problem, p.mission.traversability);
    planning::MissionGround ground;  // the one start check of every planner
    ground.dem = problem.dem.get();
    ground.classes = classes.get();
    ground.impassableDeg = p.mission.traversability.impassableDeg;
    ground.keepOut = &problem.keepOut;
    planning::StartRules rules;
    rules.safetyDistance = p.mission.coordination.safetyDistance;
    rules.wayOut = true;  // the coordinator keeps every standing rover clear (issue 25)
    planning::checkMissionStarts(ground, problem.rovers, rules);
  }

  GridGeometry eventGrid(const PlanningProblem& problem, const ParamSet& params) const override {
    if (!problem.dem) return {};
    const double f = parseTeamParams(params).mission.footprint;
    const GridGeometry& g = problem.dem->geometry();
    auto along = [f](double extent) { return std::max(1, static_cast<int>(std::ceil(extent / f - 1e-9))); };
    return {along(g.heightMetres()), along(g.widthMetres()), f, f};
  }

  PlanResult run(const PlanningProblem& problem, const ParamSet& params, EventSink* sink,
                 const CancelToken* cancel) const override {
    const auto t0 = std::chrono::steady_clock::now();
    const TeamPlannerParams p = parseTeamParams(params);
    if (!problem.dem) throw Error(ErrorCode::InvalidInput, "map", "the team planners need a DEM");
    std::vector<Pose> starts;
    for (const auto& s : problem.rovers) starts.push_back({s.position.x(), s.position.y(), s.heading});
    std::optional<SinkObserver> observer;
    if (sink) observer.emplace(*sink, starts, p.mission.exceedanceLimit);
    const Raster<float> noPdm;
    TeamMissionParams mission = p.mission;
    mission.coordination.threads = problem.threads;
    mission.keepOut = problem.keepOut;  // applied to the classes in runTeamMission
    // The simulated rover climbs against the map's body's gravity (issue 11: body-aware defaults);
    // the model's own default (Mars, paper 001's site) when the CRS names no known body.
    if (problem.body != terrain::Body::Unknown) mission.coordination.model.gravity = terrain::bodyGravity(problem.body);
    const auto classes = classesFor(problem, mission.traversability);
    TeamMissionResult r = runTeamMission(*problem.dem, *classes, problem.pdm ? *problem.pdm : noPdm,
                                         starts, mission, hybrid_, observer ? &*observer : nullptr,
                                         cancel);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    PlanResult out = toPlanResult(r, p, hybrid_, wall);
    out.assumptions.push_back({"body", terrain::bodyName(problem.body)});
    out.assumptions.push_back({"gravity", problem.body != terrain::Body::Unknown ? "the map's body"
                                                                               : "default (Mars)"});
    if (sink) sink->incidents(out.incidents, true);
    if (sink && !out.cancelled) {
      sink->metrics(out.metrics);
      observer->replay(r, p.poseInterval, p.mission.coordination.controller.samplePeriod, cancel);
      if (cancel && cancel->cancelled()) {
        out.cancelled = true;
        out.stopReason = StopReason::Cancelled;
      }
    }
    return out;
  }

 private:
  // The traversability classes of the last map planned on, kept while the map lives: a mission
  // is validated when it is queued and run later on the same map, and a map serves many missions,
  // so the classes are computed once per map and thresholds, not once per call. Memory: one byte
  // per map cell (at most 50 MB for the server's largest map), one map at a time.
  std::shared_ptr<const Raster<std::uint8_t>> classesFor(
      const PlanningProblem& problem, const terrain::TraversabilityParams& params) const {
    {
      std::lock_guard lock(cacheMutex_);
      if (cachedDem_.expired()) cachedClasses_.reset();  // the map is gone: so are its classes
      if (cachedClasses_ && cachedDem_.lock() == problem.dem &&
          cachedParams_.highRiskDeg == params.highRiskDeg &&
          cachedParams_.impassableDeg == params.impassableDeg)
        return cachedClasses_;
    }
    // On the threads the caller granted (a server worker's share, not every core).
    auto classes = std::make_shared<const Raster<std::uint8_t>>(
        terrain::traversability(*problem.dem, params, false, problem.threads).classes);
    std::lock_guard lock(cacheMutex_);
    cachedDem_ = problem.dem;
    cachedParams_ = params;
    cachedClasses_ = classes;
    return classes;
  }

  bool hybrid_;
  mutable std::mutex cacheMutex_;
  mutable std::weak_ptr<const terrain::Dem> cachedDem_;
  mutable terrain::TraversabilityParams cachedParams_;
  mutable std::shared_ptr<const Raster<std::uint8_t>> cachedClasses_;
};

}  // namespace

std::unique_ptr<Planner> makeTeamSearchPlanner() { return std::make_unique<TeamPlanner>(false); }
std::unique_ptr<Planner> makeHybridPlanner() { return std::make_unique<TeamPlanner>(true); }

}  // namespace rover::team
