// Issue 22, "memory returned after a mission": once a mission has ended, the process's resident
// size is back within 10 % of where it was before the mission. The baseline is taken after a
// one-step mission on the same map (what the server keeps per map — the DEM at the coverage cell,
// its layers — is then loaded) with the heap trimmed; the mission ends when the server has let
// it go (waitFinished: final status, result stored, heap trimmed by the worker). What the server
// keeps on purpose stays counted: the streams of the latest 32 finished missions (bounded by
// MissionManager::rememberFinished), so a viewer that joins later gets the final state.
// Not run in the sanitizer build (ROVER_SANITIZED): ASan's shadow memory and quarantine make RSS
// figures meaningless there; the Release suite runs them.
#include <doctest/doctest.h>
#include <malloc.h>

#include <fstream>
#include <string>

#include "api_server.hpp"
#include "process_memory.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::TempDir;
using nlohmann::json;

namespace {

using rover::test::kSanitized;
using rover::test::statusBytes;

std::uint64_t residentBytes() { return statusBytes("VmRSS"); }

json rovers(int count) {
  json out = json::array();
  for (int k = 0; k < count; ++k)
    out.push_back({{"x", 60.5 + 4.0 * (k % 4)}, {"y", 60.5 + 4.0 * (k / 4)}, {"heading", 0}});
  return out;
}

// Runs `body` on the default map after a one-step `warm` run of it; checks the resident size.
void checkReturned(json body, const json& warmParams) {
  TempDir d;
  ApiServer s(d.str("data"));
  body["map"] = s.defaultMap();
  json warm = body;
  warm["params"].update(warmParams);
  auto w = s.postJson("/api/missions", warm);
  REQUIRE(w.status == 202);
  s.waitFinished(w.json()["id"]);
  ::malloc_trim(0);
  const std::uint64_t before = residentBytes();
  auto r = s.postJson("/api/missions", body);
  REQUIRE(r.status == 202);
  const json m = s.waitFinished(r.json()["id"], 120);
  const std::uint64_t after = residentBytes();
  MESSAGE(body["planner"].get<std::string>() << " " << body["params"].dump() << ": " << m["status"]
                                             << "; resident " << before / 1e6 << " MB before, " << after / 1e6
                                             << " MB after");
  CHECK((m["status"] == "succeeded" || m["status"] == "completed_with_warnings"));
  CHECK(before > 0);
  CHECK(after * 10 <= before * 11);
}

}  // namespace

TEST_CASE("memory returned: within 10 % after a coverage mission" * doctest::skip(kSanitized)) {
  checkReturned({{"planner", "coverage"},
                 {"rovers", rovers(4)},
                 {"params", {{"frontier", false}, {"coverage", 1}, {"max_steps", 20000}}}},
                {{"max_steps", 1}});
}

TEST_CASE("memory returned: within 10 % after a team mission (swinton's lhc_gw_conv route)" * doctest::skip(kSanitized)) {
  checkReturned({{"planner", "team-search"}, {"rovers", rovers(4)}, {"params", {{"route", "lhc_gw_conv"}}}},
                {{"targets", 1}});
}
