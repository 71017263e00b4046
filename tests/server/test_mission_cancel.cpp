// Issue 22, "cancel within 1 s": a cancelled mission is final when the cancel request returns,
// whatever it still has to store; its partial result comes after, and no client reads it half
// written in between. The duration itself is a benchmark's (tests/bench/cancel_latency.py); here
// the order of events: a planner held after it stopped keeps the partial write from starting,
// and the status is final all the same.
#include <doctest/doctest.h>

#include <memory>
#include <string>

#include "api_server.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;

namespace {

// The coverage planner, under another name, that once cancelled holds its worker (between the
// planner's return and the result's write) until the test opens `release`.
class HeldPlanner : public Planner {
 public:
  HeldPlanner(const Planner& inner, test::Gate& release) : inner_(inner), release_(release) {}
  std::string name() const override { return "held-coverage"; }
  std::string summary() const override { return inner_.summary(); }
  std::vector<ParamInfo> params() const override { return inner_.params(); }
  const PlannerSpecs& specs() const override { return inner_.specs(); }
  void checkParams(const ParamSet& p) const override { inner_.checkParams(p); }
  ParamSet mapDefaults(const GridGeometry& map, terrain::Body body) const override { return inner_.mapDefaults(map, body); }
  MapGround groundOnMap(const GridGeometry& map, const ParamSet& p) const override { return inner_.groundOnMap(map, p); }
  MemoryEstimate memoryEstimate(const GridGeometry& map, const MapGround& ground, int rovers, bool pdm,
                                ParamSet& p) const override {
    return inner_.memoryEstimate(map, ground, rovers, pdm, p);
  }
  std::vector<RoverStart> defaultStarts(const PlanningProblem& problem, const ParamSet& p, int rovers,
                                        std::uint64_t seed) const override {
    return inner_.defaultStarts(problem, p, rovers, seed);
  }
  void validate(const PlanningProblem& problem, const ParamSet& p) const override { inner_.validate(problem, p); }
  GridGeometry eventGrid(const PlanningProblem& problem, const ParamSet& p) const override {
    return inner_.eventGrid(problem, p);
  }
  PlanResult run(const PlanningProblem& problem, const ParamSet& p, EventSink* sink,
                 const CancelToken* cancel) const override {
    PlanResult r = inner_.run(problem, p, sink, cancel);
    if (cancel && cancel->cancelled()) release_.wait();
    return r;
  }

 private:
  const Planner& inner_;
  test::Gate& release_;
};

// Registers the held planner on `s` and returns a mission of it on the default map: one rover at
// 5 steps a second, covering until cancelled.
json heldMission(ApiServer& s, test::Gate& release) {
  s.planners.add(std::make_unique<HeldPlanner>(s.planners.get("coverage"), release));
  return {{"map", s.defaultMap()},
          {"planner", "held-coverage"},
          {"rovers", {{{"x", 20.5}, {"y", 20.5}, {"heading", 0}}}},
          {"params", {{"frontier", false}, {"coverage", 1}}},
          {"pace", 5}};
}

}  // namespace

TEST_CASE("mission cancel: the status is final when the cancel returns, the partial result is stored after") {
  TempDir d;
  ApiServer s(d.str("data"));
  test::Gate release;
  const json body = heldMission(s, release);
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const std::string id = r.json()["id"];
  s.waitStarted(id);
  REQUIRE(s.status(id) == "running");
  const std::string path = "/api/missions/" + id;

  auto cancelled = request(s.port(), "DELETE", path);
  CHECK(cancelled.status == 202);
  CHECK(cancelled.json()["status"] == "cancelling");
  // The worker is held before it writes anything: the status is final all the same, and says
  // its result is to come.
  json m = s.get(path).json();
  CHECK(m["status"] == "cancelled");
  CHECK(m["message"] == "cancelled by request");
  CHECK(m["result"] == "pending");
  CHECK_FALSE(m["finished_at"].get<std::string>().empty());
  // Meanwhile its files answer 409 not_ready (never a part of a file), a second DELETE neither
  // deletes the folder being written nor cancels again, and the memory stays reserved.
  for (const char* file : {"result.json", "result.geojson", "result.csv"})
    checkError(s.get(path + "/" + file), 409, "not_ready", "id");
  checkError(request(s.port(), "DELETE", path), 409, "not_finished", "id");
  CHECK(s.manager.resultPending(id));
  CHECK(s.manager.memoryReserved() > 0);

  release.open();
  m = s.waitFinished(id);
  CHECK(m["status"] == "cancelled");
  CHECK(m["result"] == "ready");
  CHECK(m["metrics"].is_object());  // the partial result's, written with it
  CHECK(s.manager.memoryReserved() == 0);
  // The partial result a user expects: the moves made before the cancel.
  auto result = s.get(path + "/result.json");
  REQUIRE(result.status == 200);
  const json j = result.json();
  CHECK(j["cancelled"] == true);
  CHECK_FALSE(j["rovers"][0]["path"].empty());
  CHECK(s.get(path + "/result.csv").status == 200);
  // Ended now: DELETE deletes it.
  CHECK(request(s.port(), "DELETE", path).status == 200);
}

TEST_CASE("mission cancel: a queued mission is final at once, with no result to come") {
  TempDir d;
  ApiServer s(d.str("data"));
  test::Gate release;
  const json body = heldMission(s, release);
  const std::string running = s.postJson("/api/missions", body).json()["id"];
  const std::string queued = s.postJson("/api/missions", body).json()["id"];  // one worker: it waits
  REQUIRE(s.status(queued) == "queued");
  CHECK(request(s.port(), "DELETE", "/api/missions/" + queued).status == 202);
  const json m = s.get("/api/missions/" + queued).json();
  CHECK(m["status"] == "cancelled");
  CHECK(m["result"] == "none");
  checkError(s.get("/api/missions/" + queued + "/result.json"), 409, "no_result", "id");
  release.open();
  CHECK(request(s.port(), "DELETE", "/api/missions/" + running).status == 202);
  CHECK(s.waitFinished(running)["result"] == "ready");
}
