#include "core/common/error.hpp"

namespace rover {

const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidParameter:
      return "invalid_parameter";
    case ErrorCode::UnknownParameter:
      return "unknown_parameter";
    case ErrorCode::InvalidInput:
      return "invalid_input";
    case ErrorCode::NotFound:
      return "not_found";
  }
  return "error";
}

void throwInvalidParameter(const std::string& field, const std::string& message) {
  throw Error(ErrorCode::InvalidParameter, field, field + ": " + message);
}

}  // namespace rover
