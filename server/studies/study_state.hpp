#pragma once
// A server study's state (status, times, progress) and its JSON view: the API's study object,
// state.json (without "links") and the stream's frames.
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace rover::studies {

struct StudyState {
  std::string id, name;
  std::string status = "queued";  // queued | running | succeeded | cancelled | failed
  std::string message;
  std::string createdAt, startedAt, finishedAt;
  std::size_t done = 0, total = 0;
  double etaSeconds = -1;   // -1 = not known yet
  double runsPerSecond = 0;
  bool cancelRequested = false;
};
nlohmann::json toJson(const StudyState& s);
bool isEnded(const std::string& status);

}  // namespace rover::studies
