#pragma once
// The one place where failures become HTTP answers. Domain code throws DomainError (store,
// missions, studies) or core's rover::Error (bad planner input) with a code and no status; route
// code at the edge may throw http::ApiError, which names its status itself. The HTTP session
// catches whatever a handler throws and asks errorAnswer(); nothing else maps an exception.
#include <exception>
#include <string>

#include "server/errors/domain_error.hpp"
#include "server/http/http_types.hpp"

namespace rover::api {

// The HTTP status a domain refusal is answered with.
int httpStatus(Refusal code);

struct ErrorAnswer {
  http::Response response;  // {"error": {"code", "message", "field"}} with its status and headers
  std::string logDetail;    // for a 500: what the exception said, for the server's log only
};

// The answer for a thrown exception (`error` non-null):
//   http::ApiError   its status, code, field and headers;
//   DomainError      httpStatus(code), Retry-After when it carries one;
//   rover::Error     400 with its code name, its field or "body";
//   a JSON type error 400 bad_json (a body of the wrong shape);
//   anything else    500 internal, the detail kept out of the answer (it may hold server paths).
ErrorAnswer errorAnswer(std::exception_ptr error);

}  // namespace rover::api
