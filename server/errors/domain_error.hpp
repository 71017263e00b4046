#pragma once
// Why the server's domain (store, missions, studies) refuses a request: one exception family with
// a machine-readable code, like core's rover::Error, and no knowledge of HTTP. The edges translate
// it: server/api/error_table.cpp gives each code its HTTP status (and Retry-After), the CLI its
// message. core's rover::Error stays the error for bad planner input.
#include <chrono>
#include <stdexcept>
#include <string>

namespace rover {

enum class Refusal {
  BadJson,              // the document is not a JSON object of the expected shape
  UnknownField,         // a key the document may not hold; field() names it
  InvalidField,         // a value out of range or of the wrong type; field() names it
  TooManyRuns,          // a study larger than the server runs
  MissionTooLarge,      // one mission's memory estimate exceeds the whole mission budget
  TooLarge,             // one stored object exceeds a map's whole disk budget
  QueueFull,            // the mission queue is full: retry later
  MemoryBusy,           // the missions running and queued hold the memory budget: retry later
  TooManyStudies,       // the study queue is full: retry later
  Unavailable,          // the server is shutting down
  InsufficientStorage,  // the disk (or the file size limit) is full
  DiskBudgetFull,       // a disk budget (the map's or the server's) is full
};

// The code's name as clients see it ("queue_full").
const char* refusalName(Refusal code);

class DomainError : public std::runtime_error {
 public:
  DomainError(Refusal code, const std::string& message, std::string field = "")
      : std::runtime_error(message), code_(code), field_(std::move(field)) {}
  Refusal refusal() const { return code_; }
  std::string code() const { return refusalName(code_); }
  // The offending field ("" when the refusal is not about one field).
  const std::string& field() const { return field_; }
  // When a refusal for a passing condition (a full queue) is worth retrying; zero for none.
  std::chrono::seconds retryAfter() const { return retryAfter_; }
  DomainError& retryAfter(std::chrono::seconds wait) {
    retryAfter_ = wait;
    return *this;
  }

 private:
  Refusal code_;
  std::string field_;
  std::chrono::seconds retryAfter_{0};
};

}  // namespace rover
