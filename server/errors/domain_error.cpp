#include "server/errors/domain_error.hpp"

namespace rover {

const char* refusalName(Refusal code) {
  switch (code) {
    case Refusal::BadJson: return "bad_json";
    case Refusal::UnknownField: return "unknown_field";
    case Refusal::InvalidField: return "invalid_field";
    case Refusal::TooManyRuns: return "too_many_runs";
    case Refusal::MissionTooLarge: return "mission_too_large";
    case Refusal::TooLarge: return "too_large";
    case Refusal::QueueFull: return "queue_full";
    case Refusal::MemoryBusy: return "memory_busy";
    case Refusal::TooManyStudies: return "too_many_studies";
    case Refusal::Unavailable: return "unavailable";
    case Refusal::InsufficientStorage: return "insufficient_storage";
    case Refusal::DiskBudgetFull: return "disk_budget_full";
  }
  return "internal";
}

}  // namespace rover
