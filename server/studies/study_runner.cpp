#include "server/studies/study_runner.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <ctime>
#include <exception>
#include <filesystem>
#include <limits>
#include <mutex>
#include <thread>

#include "core/common/parallel.hpp"
#include "maps/dem_io.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/problems/problem_builder.hpp"

namespace rover::studies {

namespace {

namespace fs = std::filesystem;

// CPU seconds of the calling thread: with mission_threads = 1 a run's own cost, whatever else the
// machine is doing (its wall time is not, on a shared machine).
double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::string hostName() {
  char buf[256] = {0};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

const Series* findSeries(const PlanResult& r, const std::string& key) {
  for (const auto& s : r.series)
    if (s.key == key) return &s;
  return nullptr;
}

double metricOr(const PlanResult& r, const std::string& key, double fallback) {
  for (const auto& m : r.metrics)
    if (m.key == key) return m.value;
  return fallback;
}

// `points` samples of a curve, evenly spaced in index, first and last kept.
Curve sampled(const Series& s, int points) {
  Curve c{s.key, {}, {}};
  const std::size_t n = std::min(s.x.size(), s.y.size());
  if (points <= 0 || n == 0) return c;
  const auto k = static_cast<std::size_t>(points);
  if (n <= k) {
    c.x.assign(s.x.begin(), s.x.begin() + static_cast<long>(n));
    c.y.assign(s.y.begin(), s.y.begin() + static_cast<long>(n));
    return c;
  }
  for (std::size_t j = 0; j < k; ++j) {
    const std::size_t i = k == 1 ? n - 1 : (j * (n - 1) + (k - 1) / 2) / (k - 1);
    c.x.push_back(s.x[i]);
    c.y.push_back(s.y[i]);
  }
  return c;
}

// The team curve's probability at mean distance `d` per rover (linear between points); NaN when
// the team never got that far.
double probabilityAt(const Series& curve, double d) {
  const auto& x = curve.x;
  const auto& y = curve.y;
  if (x.empty() || x.back() < d) return std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 1; i < x.size(); ++i)
    if (x[i] >= d) return x[i] > x[i - 1] ? y[i - 1] + (y[i] - y[i - 1]) * (d - x[i - 1]) / (x[i] - x[i - 1]) : y[i];
  return y.back();
}

std::string levelLabel(double level) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g%%", std::round(level * 1000) / 10);
  return buf;
}

// A generated terrain as a map stored from it reads back (issue 27: a run opened as a mission must
// reproduce its row). The server stores the default map as a GeoTIFF in the body's equirectangular
// CRS and loads it as any map: the loader measures a cell's ground width at the map's centre
// latitude, 0.24999999994 m for the default map's 0.25 m, so the generated raster and the stored
// map differ in the last digits and every RRT* tree after them (mean trajectory 41.30 m in the
// study's row against 35.48 m as a mission, same seed). The study's world goes through the same
// write and load; the file is deleted at once.
terrain::Dem asStoredMap(const terrain::Dem& generated) {
  static std::atomic<unsigned> counter{0};
  const fs::path path = fs::temp_directory_path() /
                        ("roverplan-terrain-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tif");
  struct Remove {
    fs::path p;
    ~Remove() {
      std::error_code ec;
      fs::remove(p, ec);
    }
  } remove{path};
  maps::writeGeoTiff(path.string(), generated.z);
  return maps::loadDem(path.string()).dem;
}

std::shared_ptr<const terrain::Dem> loadMap(const WorldSpec& w, const std::string& field) {
  try {
    if (w.kind == WorldSpec::Kind::Terrain)
      return std::make_shared<const terrain::Dem>(asStoredMap(maps::generateTerrain(w.terrain)));
    maps::LoadOptions lo;
    lo.cellSize = w.cellSize;
    if (w.cropM > 0) {
      // The centre square of side crop_m, in the file's CRS (metres).
      maps::LoadedDem probe = maps::loadDem(w.demPath);
      const auto& gt = probe.dem.z.geo.geotransform;
      const GridGeometry& g = probe.dem.geometry();
      const double cx = gt[0] + gt[1] * g.cols / 2, cy = gt[3] + gt[5] * g.rows / 2;
      lo.crop = std::array<double, 4>{cx - w.cropM / 2, cy - w.cropM / 2, w.cropM, w.cropM};
    }
    return std::make_shared<const terrain::Dem>(maps::loadDem(w.demPath, lo).dem);
  } catch (const Error& e) {
    throw Error(e.code(), field, field + ": " + e.what());
  }
}

}  // namespace

StudyRunner::StudyRunner(StudySpec spec)
    : spec_(std::move(spec)), registry_(makeBuiltinRegistry()), host_(hostName()) {
  for (std::size_t w = 0; w < spec_.worlds.size(); ++w) {
    const WorldSpec& world = spec_.worlds[w];
    const std::string field = "worlds[" + std::to_string(w) + "]." +
                              (world.kind == WorldSpec::Kind::Dem ? "dem" : world.kind == WorldSpec::Kind::Terrain ? "terrain" : "grid");
    maps_.push_back(world.kind == WorldSpec::Kind::Grid ? nullptr : loadMap(world, field));
  }
  // Coverage on a map: the grid world laid on it is the same for every run of a configuration.
  for (const auto& c : spec_.configurations) {
    std::shared_ptr<const PlanningProblem> p;
    const Planner& planner = registry_.get(c.point.planner);
    if (planner.specs().ground == Ground::CoverageGrid && maps_[c.world]) {
      const auto& dem = maps_[c.world];
      try {
        p = std::make_shared<const PlanningProblem>(
            problems::problemOnMap(planner.groundOnMap(dem->geometry(), c.point.params), dem));
      } catch (const Error& e) {
        const std::string field = "worlds[" + std::to_string(c.world) + "]";
        throw Error(e.code(), field, field + " (" + c.name + "): " + e.what());
      }
    }
    mapProblems_.push_back(std::move(p));
  }
}

std::optional<RunRow> StudyRunner::runOne(std::size_t runIndex, const CancelToken* cancel) const {
  const Configuration& c = spec_.configOf(runIndex);
  RunRow row;
  row.runIndex = static_cast<std::int64_t>(runIndex);
  row.configId = c.id;
  row.replicate = static_cast<std::int64_t>(spec_.replicateOf(runIndex));
  row.seed = runSeed(spec_.masterSeed, spec_.replicateOf(runIndex));
  row.host = host_;
  const Planner& planner = registry_.get(c.point.planner);
  const PlannerSpecs& specs = planner.specs();
  ParamSet params = c.point.params;
  const auto& dem = maps_[c.world];

  // The problem, from the one problem builder; every random choice seeded by the run's seed.
  PlanningProblem problem;
  if (specs.ground == Ground::DemAndPdm) {
    // The run's seed for the planner's own (the team planners' RRT* and slip noise).
    if (planner.hasParam("seed")) params["seed"] = static_cast<std::int64_t>(row.seed);
    std::shared_ptr<const Raster<float>> pdm;
    if (spec_.pdmComponents > 0)
      pdm = std::make_shared<const Raster<float>>(problems::randomPdm(*dem, spec_.pdmComponents, row.seed));
    problem = problems::problemOnMap(planner.groundOnMap(dem->geometry(), params), dem, pdm);
  } else if (mapProblems_[static_cast<std::size_t>(c.id)]) {
    problem = *mapProblems_[static_cast<std::size_t>(c.id)];
  } else {
    coverage::WorldParams wp = spec_.worlds[c.world].grid;
    wp.seed = row.seed;
    problem = problems::problemOnGrid(wp);
  }
  problem.rovers = planner.defaultStarts(problem, params, c.rovers, row.seed);
  problem.threads = spec_.missionThreads;
  problem.metricsOnly = true;  // a study keeps metrics and sampled curves, never tracks

  const auto w0 = std::chrono::steady_clock::now();
  const double c0 = threadCpuSeconds();
  const PlanResult r = planner.run(problem, params, nullptr, cancel);
  row.cpuSeconds = threadCpuSeconds() - c0;
  row.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  if (r.cancelled) return std::nullopt;
  row.status = enumName(r.stopReason);

  // Metrics: the study's read-outs of the curves, then every metric the planner reports (its
  // wall time is the row's wall_s, not a metric: it differs between runs of the same row).
  const bool detection = specs.progress == ProgressMeasure::Detection;
  if (!detection) {
    if (const Series* curve = findSeries(r, specs.progressSeries)) {
      const double free = metricOr(r, "free_cells", 0);
      const double reachable = free - metricOr(r, "unreachable_cells", 0);
      const double cells = metricOr(r, "cells", 1);
      for (double level : spec_.levels) {
        // As coverage::movesToReach: the first move with ceil(level · reachable) cells visited;
        // the curve's coverage (visited / free) never falls, so a binary search finds it.
        const double needed = std::ceil(level * reachable - 1e-9);
        const auto it = std::partition_point(curve->y.begin(), curve->y.end(),
                                             [&](double y) { return std::round(y * free) < needed; });
        const double ratio = it == curve->y.end() ? std::numeric_limits<double>::quiet_NaN()
                                                  : curve->x[static_cast<std::size_t>(it - curve->y.begin())] / cells;
        row.metrics.push_back({"path_length_ratio@" + levelLabel(level), ratio});
      }
      // Paper 002's runs end at the goal; one that hit the 20·n step budget is counted.
      row.metrics.push_back({"stopped_by_budget", r.stopReason == StopReason::StepBudget ? 1.0 : 0.0});
      row.curves.push_back(sampled(*curve, spec_.curvePoints));
    }
  }
  for (const auto& m : r.metrics)
    if (m.key != "plan_wall_s") row.metrics.push_back({m.key, m.value});
  if (detection) {
    // Of the legs the route asked for (slot-less ones included), the share that got there.
    const double reached = metricOr(r, "targets_reached", 0), shortLegs = metricOr(r, "targets_short", 0);
    const double skipped = metricOr(r, "targets_skipped", 0) + metricOr(r, "targets_no_slot", 0);
    const double legs = reached + shortLegs + skipped;
    row.metrics.push_back({"legs_reached_pct", legs > 0 ? 100.0 * reached / legs : 0.0});
    row.metrics.push_back({"legs_short_pct", legs > 0 ? 100.0 * shortLegs / legs : 0.0});
    row.metrics.push_back({"legs_skipped_pct", legs > 0 ? 100.0 * skipped / legs : 0.0});
    if (const Series* curve = findSeries(r, specs.progressSeries)) {
      for (double d : spec_.distances) {
        char key[32];
        std::snprintf(key, sizeof key, "p_at_%gm", d);
        row.metrics.push_back({key, probabilityAt(*curve, d)});
      }
      row.curves.push_back(sampled(*curve, spec_.curvePoints));
    }
  }
  return row;
}

std::vector<std::size_t> StudyRunner::pending(const StudyDb& db, int shardIndex, int shardCount) const {
  const std::vector<std::int64_t> done = db.doneRuns();  // ascending: walked beside the indices
  std::vector<std::size_t> out;
  auto d = done.begin();
  for (std::size_t i = static_cast<std::size_t>(shardIndex); i < spec_.runCount(); i += static_cast<std::size_t>(shardCount)) {
    while (d != done.end() && *d < static_cast<std::int64_t>(i)) ++d;
    if (d == done.end() || *d != static_cast<std::int64_t>(i)) out.push_back(i);
  }
  return out;
}

void StudyRunner::work(unsigned threads, const std::function<std::optional<std::size_t>()>& next,
                       const std::function<void(RunRow&&)>& done, const CancelToken* cancel, int rank) const {
  if (threads == 0) threads = hardwareThreads();
  std::mutex mutex;  // guards next() and the first error
  std::exception_ptr error;
  bool stop = false;
  auto worker = [&] {
    for (;;) {
      std::optional<std::size_t> i;
      {
        std::lock_guard lock(mutex);
        if (stop || (cancel && cancel->cancelled())) return;
        i = next();
      }
      if (!i) return;
      try {
        if (auto row = runOne(*i, cancel)) {
          row->rank = rank;
          done(std::move(*row));
        }
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
        stop = true;
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

RunReport StudyRunner::run(StudyDb& db, const RunOptions& o, const ProgressFn& progress) const {
  const auto t0 = std::chrono::steady_clock::now();
  db.attach(spec_);
  const std::vector<std::size_t> todo = pending(db, o.shardIndex, o.shardCount);
  RunReport report;
  for (std::size_t i = static_cast<std::size_t>(o.shardIndex); i < spec_.runCount(); i += static_cast<std::size_t>(o.shardCount))
    ++report.total;
  report.alreadyDone = report.total - todo.size();

  // Workers hand rows to `ready`; this thread commits them in batches (one writer).
  std::mutex mutex;
  std::condition_variable wake;
  std::vector<RunRow> ready;
  bool finished = false;
  std::exception_ptr error;
  std::atomic<std::size_t> next{0};
  std::thread pool([&] {
    try {
      work(o.threads, [&]() -> std::optional<std::size_t> {
            const std::size_t k = next.fetch_add(1);
            if (k >= todo.size()) return std::nullopt;
            return todo[k];
          },
          [&](RunRow&& row) {
            std::lock_guard lock(mutex);
            ready.push_back(std::move(row));
            if (ready.size() >= o.commitRuns) wake.notify_one();
          },
          o.cancel, o.rank);
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard lock(mutex);
    finished = true;
    wake.notify_one();
  });
  auto commitSpan = std::chrono::duration<double>(o.commitSeconds);
  for (bool last = false; !last;) {
    std::vector<RunRow> batch;
    {
      std::unique_lock lock(mutex);
      wake.wait_for(lock, commitSpan, [&] { return finished || ready.size() >= o.commitRuns; });
      last = finished;
      batch.swap(ready);
    }
    try {
      db.insert(batch);
    } catch (...) {
      // The disk refused the batch: stop the workers and report why.
      next.store(todo.size());
      pool.join();
      throw;
    }
    report.ran += batch.size();
    if (progress && (!batch.empty() || last)) progress(report.alreadyDone + report.ran, report.total);
  }
  pool.join();
  if (error) std::rethrow_exception(error);
  report.cancelled = o.cancel && o.cancel->cancelled();
  report.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace rover::studies
