#include "server/studies/study_state.hpp"

#include <cmath>

namespace rover::studies {

using nlohmann::json;

json toJson(const StudyState& s) {
  return {{"id", s.id},
          {"name", s.name},
          {"version", s.version},
          {"status", enumName(s.status)},
          {"message", s.message},
          {"created_at", s.createdAt},
          {"started_at", s.startedAt},
          {"finished_at", s.finishedAt},
          {"runs_done", s.done},
          {"runs_total", s.total},
          {"eta_s", s.etaSeconds < 0 ? json(nullptr) : json(std::round(s.etaSeconds))},
          {"runs_per_s", s.runsPerSecond},
          {"links",
           {{"self", "/api/studies/" + s.id},
            {"stream", "/api/studies/" + s.id + "/stream"},
            {"runs_csv", "/api/studies/" + s.id + "/runs.csv"},
            {"sqlite", "/api/studies/" + s.id + "/study.sqlite"},
            {"benchmark_db", "/api/studies/" + s.id + "/benchmark.db"}}}};
}

}  // namespace rover::studies
