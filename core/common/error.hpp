#pragma once
// The project's one exception family for misuse and bad input (DESIGN.md "Conventions").
// Expected outcomes (coverage not reached, target skipped) are status values, never exceptions.
#include <stdexcept>
#include <string>

namespace rover {

// Machine-readable codes. The server maps them to HTTP statuses, the CLI to exit status 2.
enum class ErrorCode {
  InvalidParameter,  // a value out of range or of the wrong type; field() names it
  UnknownParameter,  // a key that no planner parameter has; field() names it
  InvalidInput,      // a structurally bad input (grid too small, rover outside the map, ...)
  NotFound,          // a planner or resource name that does not exist
};

const char* errorCodeName(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, std::string field, const std::string& message)
      : std::runtime_error(message), code_(code), field_(std::move(field)) {}
  ErrorCode code() const { return code_; }
  // The offending field ("" when the error is not about one field).
  const std::string& field() const { return field_; }

 private:
  ErrorCode code_;
  std::string field_;
};

// Shorthand for the most common case: a parameter out of range.
[[noreturn]] void throwInvalidParameter(const std::string& field, const std::string& message);

}  // namespace rover
