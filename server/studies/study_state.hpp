#pragma once
// A server study's state (status, times, progress) and its JSON view: the API's study object,
// state.json (without "links") and the stream's frames.
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "server/store/run_status.hpp"

namespace rover::studies {

struct StudyState {
  std::string id, name;
  long long version = 1;  // 1 when submitted, +1 per rename (issue 26)
  RunStatus status = RunStatus::Queued;  // one of kStudyStatuses
  std::string message;
  std::string createdAt, startedAt, finishedAt;
  std::size_t done = 0, total = 0;
  double etaSeconds = -1;   // -1 = not known yet
  double runsPerSecond = 0;
  bool cancelRequested = false;
};
nlohmann::json toJson(const StudyState& s);

}  // namespace rover::studies
