#pragma once
// Where a mission or a study is in its life, one enum for both: the database rows, the API's JSON,
// the live streams and OpenAPI carry the names in the table below, and isFinal is the one "is it
// over" rule (the page's twin is web/js/outcomes.js, checked against this table by a test).
#include <array>
#include <optional>
#include <string_view>

#include "core/common/enum_names.hpp"

namespace rover {

enum class RunStatus {
  Queued,
  Running,
  Succeeded,
  CompletedWithWarnings,  // missions: ran to the end, with something the user must be told
  Failed,
  Cancelled,
  Interrupted,  // missions: the server stopped while it was queued or running
};

template <>
struct EnumNames<RunStatus> {
  static constexpr std::array<EnumName<RunStatus>, 7> table{{
      {RunStatus::Queued, "queued"},
      {RunStatus::Running, "running"},
      {RunStatus::Succeeded, "succeeded"},
      {RunStatus::CompletedWithWarnings, "completed_with_warnings"},
      {RunStatus::Failed, "failed"},
      {RunStatus::Cancelled, "cancelled"},
      {RunStatus::Interrupted, "interrupted"},
  }};
};

// A status a run does not leave: every one but queued and running.
constexpr bool isFinal(RunStatus s) { return s != RunStatus::Queued && s != RunStatus::Running; }

// The statuses a study takes (it is never interrupted: a restart queues it again, and its
// warnings live in its summary), in table order, for OpenAPI.
constexpr std::array<RunStatus, 5> kStudyStatuses{RunStatus::Queued, RunStatus::Running, RunStatus::Succeeded,
                                                  RunStatus::Failed, RunStatus::Cancelled};

}  // namespace rover
