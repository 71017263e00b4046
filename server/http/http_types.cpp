#include "server/http/http_types.hpp"

namespace rover::http {

std::string Request::header(const std::string& lowerName) const {
  auto it = headers.find(lowerName);
  return it == headers.end() ? std::string() : it->second;
}

Response Response::json(int status, const nlohmann::json& j) {
  Response r;
  r.status = status;
  r.contentType = "application/json";
  // Replace invalid UTF-8 rather than throwing from inside a response builder.
  r.body = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return r;
}

Response Response::error(int status, const std::string& code, const std::string& message,
                         const std::string& field) {
  // Every error has the same three keys (DESIGN.md); "" when no one field is at fault (a full
  // queue, a busy server, an internal error).
  nlohmann::json e = {{"code", code}, {"message", message}, {"field", field}};
  return json(status, {{"error", e}});
}

}  // namespace rover::http
