#include "server/cli/team_sweep.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <limits>
#include <map>
#include <mutex>
#include <ostream>

#include "core/common/parallel.hpp"
#include "core/pdm/pdm.hpp"
#include "core/team/team_mission.hpp"
#include "maps/dem_io.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/cli/arg_parser.hpp"

namespace rover::cli {

const std::vector<double>& teamSweepDistances() {
  static const std::vector<double> d{100, 200, 300, 400, 600};
  return d;
}

namespace {

struct Site {
  std::string name;
  terrain::Dem dem;
};

struct Config {
  std::string name;
  team::RouteMethod route;
  bool hybrid;
  team::CoordinationMode mode = team::CoordinationMode::Timed;
};

// CPU seconds of the calling thread: a mission runs on one thread here, so this is its cost
// whatever else the machine is doing (the wall time is not, on a shared machine).
double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The team curve's probability at mean distance `d` per rover (linear between points); NaN when
// the team never got that far.
double probabilityAt(const std::vector<std::pair<double, double>>& curve, double d) {
  if (curve.empty() || curve.back().first < d) return std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 1; i < curve.size(); ++i) {
    if (curve[i].first >= d) {
      const auto& [x0, y0] = curve[i - 1];
      const auto& [x1, y1] = curve[i];
      return x1 > x0 ? y0 + (y1 - y0) * (d - x0) / (x1 - x0) : y1;
    }
  }
  return curve.back().second;
}

std::vector<Site> loadSites(const TeamSweepOptions& o) {
  std::vector<Site> sites;
  maps::SyntheticTerrainParams mars;  // the default map: mars, 600 × 600 × 0.25 m, seed 1
  sites.push_back({"mars600", maps::generateTerrain(mars)});
  if (!o.hirisePath.empty()) {
    // Centre 150 × 150 m of the 348 × 337 m HiRISE patch, in the file's CRS (metres).
    maps::LoadOptions lo;
    lo.cellSize = 0.25;
    try {
      maps::LoadedDem probe = maps::loadDem(o.hirisePath);
      const auto& gt = probe.dem.z.geo.geotransform;
      const GridGeometry& g = probe.dem.geometry();
      const double cx = gt[0] + gt[1] * g.cols / 2, cy = gt[3] + gt[5] * g.rows / 2;
      lo.crop = std::array<double, 4>{cx - 75, cy - 75, 150, 150};
      sites.push_back({"hirise150", maps::loadDem(o.hirisePath, lo).dem});
    } catch (const Error& e) {
      throw UsageError(o.hirisePath + ": " + e.what());
    }
  }
  return sites;
}

}  // namespace

SweepOutcome runTeamSweep(const TeamSweepOptions& o, std::ostream& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<Site> sites = loadSites(o);
  std::vector<Config> all{{"lhc_gw_conv", team::RouteMethod::LhcGwConv, false},
                          {"lhc", team::RouteMethod::Lhc, false},
                          {"lawnmower", team::RouteMethod::Lawnmower, false},
                          {"hybrid", team::RouteMethod::LhcGwConv, true}};
  std::vector<Config> picked;
  for (const auto& c : all)
    if (o.configs.empty() || std::find(o.configs.begin(), o.configs.end(), c.name) != o.configs.end())
      picked.push_back(c);
  if (picked.empty()) throw UsageError("invalid value for --configs: none of lhc_gw_conv, lhc, lawnmower, hybrid");
  const std::vector<std::string> modes = o.coordination.empty() ? std::vector<std::string>{"timed"} : o.coordination;
  std::vector<Config> configs;
  for (const auto& mode : modes) {
    if (mode != "timed" && mode != "paper")
      throw UsageError("invalid value for --coordination: " + mode + " (timed, paper)");
    for (Config c : picked) {
      if (mode == "paper") {
        c.name += "+paper";
        c.mode = team::CoordinationMode::Paper;
      }
      configs.push_back(c);
    }
  }

  // Per site: the PDMs and the formation starts at the site centre.
  struct Job {
    std::size_t site, config;
    int run;
  };
  std::vector<Job> jobs;
  for (std::size_t s = 0; s < sites.size(); ++s)
    for (int r = 0; r < o.runs; ++r)
      for (std::size_t c = 0; c < configs.size(); ++c) jobs.push_back({s, c, r});

  team::TeamMissionParams base;
  base.route.targets = o.targets;
  base.coordination.threads = o.missionThreads;  // 1: the sweep is parallel over missions
  // The traversability classes once per site, not once per mission.
  std::vector<Raster<std::uint8_t>> classes;
  std::vector<std::vector<team::Pose>> starts;
  for (const auto& site : sites) {
    const GridGeometry& g = site.dem.geometry();
    classes.push_back(terrain::traversability(site.dem, base.traversability).classes);
    starts.push_back(team::formationStarts(site.dem, classes.back(), base, {g.widthMetres() / 2, g.heightMetres() / 2}, o.rovers));
  }

  // Metric values per (site/config, metric), in run order.
  std::vector<std::map<std::string, double>> values(jobs.size());
  std::mutex mutex;
  std::size_t done = 0;
  parallelFor(jobs.size(), o.threads, [&](std::size_t j) {
    const Job& job = jobs[j];
    const Site& site = sites[job.site];
    const std::uint64_t seed = o.firstSeed + static_cast<std::uint64_t>(job.run);
    const GridGeometry& g = site.dem.geometry();
    std::vector<std::uint8_t> valid(g.cellCount());
    for (int i = 0; i < g.cellCount(); ++i) valid[i] = !std::isnan(site.dem.z.at(i));
    const Raster<float> pdm = pdm::discretise(pdm::randomGaussians(g, 4, seed), g, valid);
    team::TeamMissionParams p = base;
    p.routeMethod = configs[job.config].route;
    p.coordination.mode = configs[job.config].mode;
    p.seed = seed;
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = threadCpuSeconds();
    team::TeamMissionResult r = team::runTeamMission(site.dem, classes[job.site], pdm, starts[job.site], p,
                                                    configs[job.config].hybrid);
    const double cpu = threadCpuSeconds() - c0;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    const team::TeamMetrics& m = r.metrics;
    auto& v = values[j];
    v["mean_trajectory_m"] = m.meanTrajectoryM;
    v["mission_time_min"] = m.missionTimeS / 60;
    v["samples"] = static_cast<double>(m.samples);
    v["exceedances"] = static_cast<double>(m.exceedances);
    v["exceedance_fraction"] = m.exceedanceFraction;
    v["collisions"] = m.collisions;
    v["min_separation_m"] = m.minSeparationM;
    v["accumulated_probability"] = m.accumulatedProbability;
    v["single_rover_probability"] = m.singleRoverProbability;
    v["route_score"] = m.routeScore;
    v["targets_reached"] = m.targetsReached;
    v["targets_skipped"] = m.targetsSkipped;
    v["targets_short"] = m.targetsShort;
    v["targets_no_slot"] = m.targetsNoSlot;
    // Of the legs the route asked for (slot-less ones included), the share that got there.
    const double legs = m.targetsReached + m.targetsShort + m.targetsSkipped + m.targetsNoSlot;
    v["legs_reached_pct"] = legs > 0 ? 100.0 * m.targetsReached / legs : 0.0;
    v["legs_short_pct"] = legs > 0 ? 100.0 * m.targetsShort / legs : 0.0;
    v["legs_skipped_pct"] = legs > 0 ? 100.0 * (m.targetsSkipped + m.targetsNoSlot) / legs : 0.0;
    v["unreachable_probability"] = r.reachability.unreachableMass;
    v["replans"] = m.replans;
    v["rrt_calls"] = m.rrtCalls;
    v["warnings"] = static_cast<double>(team::missionWarnings(r).size());
    v["plan_wall_s"] = wall;
    v["plan_cpu_s"] = cpu;
    for (double d : teamSweepDistances()) {
      char key[32];
      std::snprintf(key, sizeof key, "p_at_%gm", d);
      v[key] = probabilityAt(r.curves.team, d);
    }
    std::lock_guard lock(mutex);
    ++done;
    progress << "  [" << done << "/" << jobs.size() << "] " << site.name << " " << configs[job.config].name
             << " pdm " << seed << ": " << std::fixed << std::setprecision(1) << m.meanTrajectoryM
             << " m, p " << std::setprecision(3) << m.accumulatedProbability << ", " << m.collisions
             << " collisions, " << m.exceedances << " exceedances, " << std::setprecision(1) << wall << " s\n"
             << std::flush;
  });

  SweepOutcome out;
  out.totalRuns = jobs.size();
  for (std::size_t s = 0; s < sites.size(); ++s) {
    for (std::size_t c = 0; c < configs.size(); ++c) {
      const std::string name = sites[s].name + "/" + configs[c].name;
      std::map<std::string, std::vector<double>> series;
      std::vector<std::string> order;
      for (std::size_t j = 0; j < jobs.size(); ++j) {
        if (jobs[j].site != s || jobs[j].config != c) continue;
        for (const auto& [k, v] : values[j]) {
          if (!series.count(k)) order.push_back(k);
          if (std::isfinite(v)) series[k].push_back(v);
          else series[k];
        }
      }
      for (const auto& k : order) out.rows.push_back({name, k, static_cast<std::size_t>(o.runs), summarize(series[k])});
    }
  }
  out.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace rover::cli
