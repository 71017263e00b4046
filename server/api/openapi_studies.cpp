// The schemas of /api/studies in the OpenAPI document: what server/studies/study_state.cpp,
// study_db.cpp (the summary) and server/api/study_routes.cpp write.
#include "server/api/openapi.hpp"
#include "server/api/openapi_kit.hpp"
#include "server/store/run_status.hpp"

namespace rover::api::openapi {

using nlohmann::json;
using namespace kit;

namespace {

const json kInteger = {{"type", "integer"}};
const json kObject = {{"type", "object"}};

// A study as server/studies/study_state.cpp's toJson writes it.
json study() {
  json statuses = json::array();
  for (RunStatus st : kStudyStatuses) statuses.push_back(enumName(st));
  return object({{"id", str()},
                 {"name", str()},
                 {"version", {{"type", "integer"}, {"description", "+1 per rename; send it back (If-Match) to rename."}}},
                 {"status", {{"type", "string"}, {"enum", statuses}}},
                 {"message", str("Why it failed or was queued again.")},
                 {"created_at", str()},
                 {"started_at", str()},
                 {"finished_at", str()},
                 {"runs_done", kInteger},
                 {"runs_total", kInteger},
                 {"eta_s", nullable(num("Seconds left; null until known."))},
                 {"runs_per_s", num()},
                 {"links", {{"type", "object"}, {"additionalProperties", str()}}}},
                {"id", "name", "version", "status", "runs_done", "runs_total"});
}

}  // namespace

json studySchemas() {
  json s = json::object();
  s["Study"] = study();
  s["StudyName"] = object({{"name", withMinLength(name("The study's new name, not blank."))},
                           {"version", {{"type", "integer"}, {"description", "The version read (or If-Match)."}}}},
                          {"name"}, true);
  json row = object({{"config", str()},
                     {"metric", str()},
                     {"runs", {{"type", "integer"}, {"description", "Runs of the configuration stored."}}},
                     {"n", {{"type", "integer"}, {"description", "Runs with a value."}}},
                     {"mean", nullable(num())},
                     {"std", nullable(num())},
                     {"p5", nullable(num())},
                     {"p50", nullable(num())},
                     {"p95", nullable(num())},
                     {"min", nullable(num())},
                     {"max", nullable(num())}},
                    {"config", "metric", "runs", "n"});
  s["StudySummary"] = object({{"study", str()},
                              {"runs_done", kInteger},
                              {"runs_total", kInteger},
                              {"run_wall_s", num("The runs' wall times added up.")},
                              {"rows", {{"type", "array"}, {"items", row}}}},
                             {"study", "runs_done", "runs_total", "rows"});
  s["StudyConfiguration"] = object({{"id", kInteger},
                                    {"name", str()},
                                    {"planner", str()},
                                    {"world", str()},
                                    {"rovers", kInteger},
                                    {"params", kObject}},
                                   {"id", "name", "planner", "world", "rovers", "params"});
  json detail = study();
  detail["properties"]["spec"] = {{"type", "object"}, {"description", "The study document as accepted."}};
  detail["properties"]["configurations"] = {{"type", "array"}, {"items", ref("StudyConfiguration")}};
  json summary = ref("StudySummary");
  detail["properties"]["summary"] = {{"type", "object"}, {"allOf", {summary}}, {"nullable", true},
                                     {"description", "Null until the first run is stored."}};
  for (const char* k : {"spec", "configurations", "summary"}) detail["required"].push_back(k);
  s["StudyDetail"] = detail;
  s["StudyPreset"] = object({{"name", str()}, {"spec", {{"type", "object"}, {"description", "A study document."}}}},
                            {"name", "spec"});
  json mission = object({{"map", str()},
                         {"planner", str()},
                         {"rovers", {{"type", "array"}, {"items", kObject}}},
                         {"params", kObject},
                         {"name", str()}},
                        {"map", "planner", "rovers", "params"});
  mission["nullable"] = true;
  s["StudyRun"] = object({{"run_index", kInteger},
                          {"config", str()},
                          {"planner", str()},
                          {"world", str()},
                          {"rovers", kInteger},
                          {"seed", {{"type", "integer"}, {"format", "int64"}}},
                          {"replicate", kInteger},
                          {"params", kObject},
                          {"mission", mission},
                          {"mission_unavailable", str("Why the run cannot be opened as a mission.")},
                          {"pdm_random", object({{"components", kInteger}, {"seed", kInteger}}, {"components", "seed"})}},
                         {"run_index", "config", "planner", "world", "rovers", "seed", "replicate", "params", "mission"});
  s["StudyRequest"] = {{"type", "object"},
                       {"description", "A study document (README \"Studies\", server/studies/study_spec.hpp) or "
                                       "{\"preset\": NAME, \"runs\": N, \"master_seed\"?, \"name\"?}."}};
  return s;
}

}  // namespace rover::api::openapi
