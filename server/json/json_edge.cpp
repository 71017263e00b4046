#include "server/json/json_edge.hpp"

#include <cstdint>
#include <string>

#include "server/http/http_types.hpp"

namespace rover::json {

using http::ApiError;

int jsonNestingDepth(std::string_view text, int stopAt) {
  int depth = 0, deepest = 0;
  bool inString = false, escaped = false;
  for (const char ch : text) {
    if (inString) {
      if (escaped) escaped = false;
      else if (ch == '\\') escaped = true;
      else if (ch == '"') inString = false;
      continue;
    }
    switch (ch) {
      case '"':
        inString = true;
        break;
      case '[':
      case '{':
        if (++depth > deepest) {
          deepest = depth;
          if (deepest > stopAt) return deepest;
        }
        break;
      case ']':
      case '}':
        // An unbalanced closer is invalid JSON; the parser reports it.
        if (depth > 0) --depth;
        break;
      default:
        break;
    }
  }
  return deepest;
}

nlohmann::json parseJsonLimited(std::string_view text, const JsonLimits& limits, bool requireObject) {
  // Depth first (one cheap pass over what the HTTP layer already holds, itself bounded), so a
  // nesting attack is named as such even when it is also too large.
  if (jsonNestingDepth(text, limits.maxDepth) > limits.maxDepth)
    throw ApiError(400, "too_deep",
                   "the JSON body nests arrays/objects deeper than " + std::to_string(limits.maxDepth) + " levels",
                   "body");
  if (text.size() > limits.maxBytes)
    throw ApiError(413, "payload_too_large",
                   "the JSON body is " + std::to_string(text.size()) + " bytes, over the limit of " +
                       std::to_string(limits.maxBytes),
                   "body");
  nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) throw ApiError(400, "bad_json", "the request body is not valid JSON", "body");
  if (requireObject && !j.is_object())
    throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  return j;
}

namespace {
// Code points of a UTF-8 string, or -1 if it is not valid UTF-8 (overlong forms, surrogates and
// values over U+10FFFF rejected, as nlohmann's lexer does for JSON strings).
long utf8Length(std::string_view s) {
  long count = 0;
  for (std::size_t i = 0; i < s.size(); ++count) {
    const auto b = static_cast<unsigned char>(s[i]);
    std::size_t len = 0;
    std::uint32_t cp = 0;
    if (b < 0x80) len = 1, cp = b;
    else if ((b & 0xE0) == 0xC0) len = 2, cp = b & 0x1F;
    else if ((b & 0xF0) == 0xE0) len = 3, cp = b & 0x0F;
    else if ((b & 0xF8) == 0xF0) len = 4, cp = b & 0x07;
    else return -1;
    if (i + len > s.size()) return -1;
    for (std::size_t k = 1; k < len; ++k) {
      const auto c = static_cast<unsigned char>(s[i + k]);
      if ((c & 0xC0) != 0x80) return -1;
      cp = (cp << 6) | (c & 0x3F);
    }
    static constexpr std::uint32_t kMinOf[] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < kMinOf[len] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return -1;
    i += len;
  }
  return count;
}
}  // namespace

void checkName(std::string_view name, const std::string& field) {
  const long n = utf8Length(name);
  if (n < 0) throw ApiError(400, "invalid_field", field + " must be valid UTF-8 text", field);
  // No control characters (NUL among them): a name is shown in lists, logs and file headers.
  for (unsigned char c : name)
    if (c < 0x20 || c == 0x7f)
      throw ApiError(400, "invalid_field", field + " must not hold control characters", field);
  if (static_cast<std::size_t>(n) > kMaxNameChars)
    throw ApiError(400, "invalid_field",
                   field + " is " + std::to_string(n) + " characters long, over the limit of " +
                       std::to_string(kMaxNameChars),
                   field);
}

}  // namespace rover::json
