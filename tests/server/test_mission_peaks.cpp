// Issue 22, "budgets that are true": a mission's admission estimate covers its real peak, on every
// planner. Each case runs one mission on the in-process server (its own test process under CTest)
// and measures the process's resident high-water mark over the mission, from a baseline taken
// with the heap trimmed: the kernel's VmHWM, reset first through /proc/self/clear_refs, and a
// sampler as a fallback where that reset is not allowed. The measured peak must stay within 1.5×
// the estimate the server counted against its budget, and the memory must come back afterwards
// (the finished-stream cache aside).
// Maps are the default map (150 m); missions are bounded by their steps or targets, a few seconds.
// Not run in the sanitizer build (ROVER_SANITIZED): ASan's shadow memory and quarantine make RSS
// figures meaningless there; the Release suite runs them.
#include <doctest/doctest.h>
#include <malloc.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <string>
#include <thread>

#include "api_server.hpp"
#include "process_memory.hpp"
#include "core/coverage/coverage_memory.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/team/team_memory.hpp"
#include "server/missions/mission_memory.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

using rover::test::kSanitized;
using rover::test::statusBytes;

// The process's resident peak from now on, over a baseline taken with the heap trimmed.
class PeakMeter {
 public:
  PeakMeter() {
    ::malloc_trim(0);
    base_ = statusBytes("VmRSS");
    // "5" resets the peak RSS to the current RSS (Linux 4.0+); not allowed everywhere.
    std::ofstream reset("/proc/self/clear_refs");
    reset << "5";
    reset.flush();
    hwmReset_ = reset.good() && statusBytes("VmHWM") <= base_ + (4u << 20);
    // Samples every 2 ms: the period is the meter's resolution, not a wait for anything.
    sampler_ = std::thread([this] {
      while (!stop_.load()) {
        const std::uint64_t now = statusBytes("VmRSS");
        if (now > sampled_.load()) sampled_.store(now);
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    });
  }
  ~PeakMeter() { finish(); }
  // Bytes over the baseline at the highest point since construction.
  std::uint64_t finish() {
    if (sampler_.joinable()) {
      stop_.store(true);
      sampler_.join();
    }
    std::uint64_t peak = sampled_.load();
    if (hwmReset_) peak = std::max(peak, statusBytes("VmHWM"));
    return peak > base_ ? peak - base_ : 0;
  }
  std::uint64_t base() const { return base_; }

 private:
  std::uint64_t base_ = 0;
  bool hwmReset_ = false;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sampled_{0};
  std::thread sampler_;
};

// The default map: 600 × 600 cells of 0.25 m; its default coverage grid keeps 40 000 cells.
constexpr std::int64_t kDefaultMapCells = 600 * 600;

json rovers(int count) {
  json out = json::array();
  for (int k = 0; k < count; ++k)
    out.push_back({{"x", 60.5 + 4.0 * (k % 4)}, {"y", 60.5 + 4.0 * (k / 4)}, {"heading", 0}});
  return out;
}

// The estimate the server counts for a coverage mission on the default map (as buildMission
// computes it), for the checks below.
missions::MemoryEstimate coverageEstimate(const json& params, int roverCount) {
  ParamSet ps;
  const std::int64_t requested = params.value("max_steps", std::int64_t{0});
  const GridGeometry map{600, 600, 0.25, 0.25};
  const double cell = params.contains("coverage_cell") ? params["coverage_cell"].get<double>()
                                                       : coverage::defaultCoverageCell(map, coverage::CoverageParams{}.cellBudget);
  const double cells = std::ceil(150.0 / cell - 1e-9) * std::ceil(150.0 / cell - 1e-9);
  const auto steps = coverage::stepBudget(ps, requested, static_cast<std::int64_t>(cells), roverCount);
  const bool localisation = params.contains("odometry_noise");
  return coverage::missionMemory(static_cast<std::int64_t>(cells), cell, roverCount,
                                  params.value("mode", "") == "voronoi", steps, localisation);
}

struct Run {
  json mission;
  std::uint64_t peak = 0, estimate = 0, before = 0, after = 0;
};

// Memory returned: the goal is within 10 % of before (a server process measured alone by
// tests/bench/mission_budget.py); in this test process, shared with the client and the other
// cases' leftovers, within 10 % or at least most of the peak gone (issue 22: 1.77 of 2.46 GB
// stayed).
bool memoryReturned(const Run& run) {
  return run.after <= run.before + std::max(run.peak / 2, run.before / 10);
}

// Runs `body` to its end on a fresh server and measures it; `estimate`: what the server counted.
Run measure(ApiServer& s, json body, std::uint64_t estimate) {
  body["map"] = s.defaultMap();
  // A short mission first, so what the server keeps per map (the DEM at the cell, its layers)
  // is there before the baseline: the 10 % is about what the mission itself leaves behind.
  json warm = body;
  if (body["planner"] == "coverage") warm["params"]["max_steps"] = 1;
  else warm["params"]["targets"] = 1;
  auto w = s.postJson("/api/missions", warm);
  REQUIRE(w.status == 202);
  s.waitFinished(w.json()["id"], 120);
  Run run;
  run.estimate = estimate;
  PeakMeter meter;
  run.before = meter.base();
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  run.mission = s.waitFinished(r.json()["id"], 120);
  run.peak = meter.finish();
  // The server keeps the streams of the 32 latest finished missions (their grid and trails, for
  // a viewer that joins later; the polling above rebuilt this one), by design and bounded: what
  // must come back is everything else the mission held.
  s.manager.forget(r.json()["id"]);
  // The worker trims the heap once the mission is gone: wait for the resident size to come back
  // as far as checkTrue asks (a deadline that only catches a hang).
  test::waitUntil(
      [&] {
        run.after = statusBytes("VmRSS");
        return memoryReturned(run);
      },
      "the resident size to fall back after the mission");
  MESSAGE(body["planner"].get<std::string>() << " " << body["params"].dump() << ": peak "
          << run.peak / 1e6 << " MB over " << run.before / 1e6 << " MB, estimate " << run.estimate / 1e6
          << " MB (" << static_cast<double>(run.peak) / static_cast<double>(run.estimate)
          << "x); after " << run.after / 1e6 << " MB; status " << run.mission["status"]);
  return run;
}

void checkTrue(const Run& run) {
  const std::string status = run.mission["status"];
  CHECK((status == "succeeded" || status == "completed_with_warnings"));
  CHECK(run.before > 0);  // /proc/self/status was read (the peak itself may be 0: memory reused)
  CHECK(static_cast<double>(run.peak) <= 1.5 * static_cast<double>(run.estimate));
  WARN(run.after * 10 <= run.before * 11);
  CHECK(memoryReturned(run));
}

void checkCoverage(const json& params, int roverCount) {
  TempDir d;
  ApiServer s(d.str("data"));
  json body{{"planner", "coverage"}, {"rovers", rovers(roverCount)}, {"params", params}};
  const auto estimate = coverageEstimate(params, roverCount);
  const Run run = measure(s, body, estimate.bytes);
  checkTrue(run);
  CHECK(s.manager.memoryReserved() == 0);
}

}  // namespace

// The mission (frontier off, goal 1: it never meets its goal) with its steps bounded:
// the moves and the result it writes are what the estimate must cover.
TEST_CASE("mission peaks: coverage overlap, a team that never meets its goal, stays within its estimate" * doctest::skip(kSanitized)) {
  checkCoverage({{"frontier", false}, {"coverage", 1}, {"max_steps", 20000}}, 4);
}

TEST_CASE("mission peaks: coverage voronoi stays within its estimate" * doctest::skip(kSanitized)) {
  checkCoverage({{"frontier", false}, {"coverage", 1}, {"mode", "voronoi"}, {"max_steps", 20000}}, 4);
}

TEST_CASE("mission peaks: coverage frontier with the server's default step budget stays within its estimate" * doctest::skip(kSanitized)) {
  checkCoverage({{"frontier", true}, {"coverage", 1}}, 2);
}

TEST_CASE("mission peaks: coverage with localisation error stays within its estimate" * doctest::skip(kSanitized)) {
  checkCoverage({{"frontier", false}, {"coverage", 1}, {"odometry_noise", 2.0}, {"heading_noise", 0.5},
                 {"max_steps", 20000}},
                2);
}

TEST_CASE("mission peaks: team-search stays within its estimate" * doctest::skip(kSanitized)) {
  TempDir d;
  ApiServer s(d.str("data"));
  const json params{{"targets", 6}};
  ParamSet ps;
  ps["targets"] = std::int64_t{6};
  const auto estimate = team::missionMemory(kDefaultMapCells, 2, false, ps, false);
  const Run run = measure(s, {{"planner", "team-search"}, {"rovers", rovers(2)}, {"params", params}}, estimate.bytes);
  checkTrue(run);
  CHECK(run.mission["metrics"]["targets"] == 6);
}

TEST_CASE("mission peaks: hybrid stays within its estimate" * doctest::skip(kSanitized)) {
  TempDir d;
  ApiServer s(d.str("data"));
  const json params{{"targets", 3}};
  ParamSet ps;
  ps["targets"] = std::int64_t{3};
  const auto estimate = team::missionMemory(kDefaultMapCells, 2, false, ps, true);
  const Run run = measure(s, {{"planner", "hybrid"}, {"rovers", rovers(2)}, {"params", params}}, estimate.bytes);
  checkTrue(run);
  CHECK(run.mission["metrics"]["targets"] == 3);
}
