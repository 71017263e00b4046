#include "server/api/preconditions.hpp"

#include <charconv>

namespace rover::api {

using http::ApiError;

namespace {

// Versions stay below 2^53, so they survive JavaScript numbers in the page.
constexpr long long kMaxVersion = (1LL << 53) - 1;

std::optional<long long> parseTag(std::string tag) {
  while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.pop_back();
  while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.erase(tag.begin());
  // If-Match compares strongly (RFC 9110 §13.1.1): a weak tag never names a version, and a
  // version is written one way only ("v3", not "v03"), as the ETag the server sent.
  if (tag.rfind("W/", 0) == 0) return std::nullopt;
  if (tag.size() >= 2 && tag.front() == '"' && tag.back() == '"') tag = tag.substr(1, tag.size() - 2);
  if (tag.size() < 2 || tag.size() > 17 || tag[0] != 'v') return std::nullopt;
  if (tag[1] == '0' && tag.size() > 2) return std::nullopt;
  long long v = -1;
  const char* end = tag.data() + tag.size();
  auto [p, ec] = std::from_chars(tag.data() + 1, end, v);
  if (ec != std::errc() || p != end || v < 0 || v > kMaxVersion) return std::nullopt;
  return v;
}

}  // namespace

std::optional<long long> namedVersion(const http::Request& req, const nlohmann::json* body) {
  std::optional<long long> fromHeader, fromBody;
  if (req.headers.count("if-match")) {
    fromHeader = parseTag(req.header("if-match"));
    if (!fromHeader)
      throw ApiError(400, "invalid_header",
                     "If-Match must be one strong ETag as read, \"v<N>\" (e.g. \"v3\"); a weak W/ tag, a list or * is not taken",
                     "If-Match");
  }
  if (body && body->is_object()) {
    if (auto it = body->find("version"); it != body->end() && !it->is_null()) {
      if (!it->is_number_integer() || it->get<long long>() < 0 || it->get<long long>() > kMaxVersion)
        throw ApiError(400, "invalid_field", "version must be the integer version as read", "version");
      fromBody = it->get<long long>();
    }
  }
  if (fromHeader && fromBody && *fromHeader != *fromBody)
    throw ApiError(400, "invalid_field", "If-Match and the body's version name different versions", "version");
  return fromHeader ? fromHeader : fromBody;
}

long long requiredVersion(const http::Request& req, const nlohmann::json* body, const std::string& what) {
  auto v = namedVersion(req, body);
  if (!v)
    throw ApiError(428, "precondition_required",
                   what + " already exist(s): send the version you read (If-Match: \"v<N>\" from its ETag, "
                          "or a \"version\" member), so that no one else's change is overwritten",
                   "If-Match");
  return *v;
}

ApiError versionConflict(const std::string& what, long long named, long long current, nlohmann::json currentObject) {
  ApiError e(412, "version_conflict",
             what + " changed since you read it: you sent version " + std::to_string(named) + ", it is now version " +
                 std::to_string(current) + " (error.current); nothing was written",
             "If-Match");
  e.withDetail("current", std::move(currentObject)).withHeader("ETag", etagOf(current));
  return e;
}

std::string etagOf(long long version) { return "\"v" + std::to_string(version) + "\""; }

http::Response withETag(http::Response r, long long version) {
  r.headers.emplace_back("ETag", etagOf(version));
  return r;
}

}  // namespace rover::api
