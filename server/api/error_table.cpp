#include "server/api/error_table.hpp"

#include <nlohmann/json.hpp>

#include "core/common/error.hpp"

namespace rover::api {

int httpStatus(Refusal code) {
  switch (code) {
    case Refusal::BadJson:
    case Refusal::UnknownField:
    case Refusal::InvalidField:
    case Refusal::TooManyRuns:
      return 400;
    case Refusal::MissionTooLarge:
    case Refusal::TooLarge:
      return 413;
    case Refusal::QueueFull:
    case Refusal::MemoryBusy:
    case Refusal::TooManyStudies:
      return 429;
    case Refusal::Unavailable:
      return 503;
    case Refusal::InsufficientStorage:
    case Refusal::DiskBudgetFull:
      return 507;
  }
  return 500;
}

namespace {

http::Response answer(const DomainError& e) {
  http::Response r = http::Response::error(httpStatus(e.refusal()), e.code(), e.what(), e.field());
  if (e.retryAfter().count() > 0) r.headers.emplace_back("Retry-After", std::to_string(e.retryAfter().count()));
  return r;
}

}  // namespace

ErrorAnswer errorAnswer(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const http::ApiError& e) {
    http::Response r = http::Response::error(e.status(), e.code(), e.what(), e.field());
    if (!e.details().empty()) {
      nlohmann::json body = nlohmann::json::parse(r.body);
      for (const auto& [k, v] : e.details().items()) body["error"][k] = v;
      r.body = body.dump();
    }
    r.headers = e.headers();
    return {std::move(r), ""};
  } catch (const DomainError& e) {
    return {answer(e), ""};
  } catch (const Error& e) {
    // Every error names its field: one that names none is about the request body as a whole.
    return {http::Response::error(400, errorCodeName(e.code()), e.what(), e.field().empty() ? "body" : e.field()), ""};
  } catch (const nlohmann::json::exception&) {
    return {http::Response::error(400, "bad_json", "the request body has a value of the wrong type", "body"), ""};
  } catch (const std::exception& e) {
    return {http::Response::error(500, "internal", "internal error"), e.what()};
  } catch (...) {
    return {http::Response::error(500, "internal", "unknown error"), "an exception that is not a std::exception"};
  }
}

}  // namespace rover::api
