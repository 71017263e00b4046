#include "server/json/json_edge.hpp"

#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

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
  // One set of seen keys per open object; the first key seen twice is reported after the parse
  // (the callback must not throw through nlohmann's parser).
  std::vector<std::unordered_set<std::string>> open;
  std::string duplicate;
  bool hasDuplicate = false;
  const nlohmann::json::parser_callback_t noteKeys = [&](int, nlohmann::json::parse_event_t event,
                                                         nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (event == E::object_start) open.emplace_back();
    else if (event == E::object_end && !open.empty()) open.pop_back();
    else if (event == E::key && !open.empty() && !hasDuplicate &&
             !open.back().insert(parsed.get<std::string>()).second) {
      hasDuplicate = true;
      duplicate = parsed.get<std::string>();
    }
    return true;
  };
  nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), noteKeys, false);
  if (j.is_discarded()) throw ApiError(400, "bad_json", "the request body is not valid JSON", "body");
  if (hasDuplicate)
    throw ApiError(400, "bad_json", "the request body names the key '" + shown(duplicate) + "' twice in one object",
                   shown(duplicate));
  if (requireObject && !j.is_object())
    throw ApiError(400, "bad_json", "the request body must be a JSON object", "body");
  return j;
}

namespace {

// One UTF-8 sequence at s[i]: its code point and length, or length 0 when it is not valid UTF-8
// (overlong forms, surrogates and values over U+10FFFF rejected, as nlohmann's lexer does for
// JSON strings).
struct CodePoint {
  std::uint32_t cp = 0;
  std::size_t len = 0;
};
CodePoint decode(std::string_view s, std::size_t i) {
  const auto b = static_cast<unsigned char>(s[i]);
  std::size_t len = 0;
  std::uint32_t cp = 0;
  if (b < 0x80) len = 1, cp = b;
  else if ((b & 0xE0) == 0xC0) len = 2, cp = b & 0x1F;
  else if ((b & 0xF0) == 0xE0) len = 3, cp = b & 0x0F;
  else if ((b & 0xF8) == 0xF0) len = 4, cp = b & 0x07;
  else return {};
  if (i + len > s.size()) return {};
  for (std::size_t k = 1; k < len; ++k) {
    const auto c = static_cast<unsigned char>(s[i + k]);
    if ((c & 0xC0) != 0x80) return {};
    cp = (cp << 6) | (c & 0x3F);
  }
  static constexpr std::uint32_t kMinOf[] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < kMinOf[len] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return {};
  return {cp, len};
}

}  // namespace

// C0 and DEL, C1, the zero-width and direction marks (U+200B–200F), line and paragraph separators
// (U+2028/2029), the bidi embeddings and overrides (U+202A–202E) and isolates (U+2066–2069), and
// the byte-order mark / zero-width no-break space (U+FEFF): they make a name show as something it
// is not ("Trojan Source" reordering) or break the line it is shown in.
bool isHiddenControl(std::uint32_t cp) {
  return cp < 0x20 || cp == 0x7F || (cp >= 0x80 && cp <= 0x9F) || (cp >= 0x200B && cp <= 0x200F) ||
         (cp >= 0x2028 && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069) || cp == 0xFEFF;
}

std::string nameProblem(std::string_view name) {
  std::size_t chars = 0;
  for (std::size_t i = 0; i < name.size(); ++chars) {
    const CodePoint c = decode(name, i);
    if (c.len == 0) return "must be valid UTF-8 text";
    // No control characters (NUL among them): a name is shown in lists, logs and file headers.
    if (isHiddenControl(c.cp)) return "must not hold control, zero-width or text-direction characters";
    i += c.len;
  }
  if (chars > kMaxNameChars)
    return "is " + std::to_string(chars) + " characters long, over the limit of " + std::to_string(kMaxNameChars);
  return {};
}

void checkName(std::string_view name, const std::string& field) {
  if (std::string problem = nameProblem(name); !problem.empty())
    throw ApiError(400, "invalid_field", field + " " + problem, field);
}

std::string cleanName(std::string_view raw, std::size_t maxChars) {
  std::string out;
  std::size_t chars = 0;
  for (std::size_t i = 0; i < raw.size() && chars < maxChars;) {
    const CodePoint c = decode(raw, i);
    if (c.len == 0) {
      ++i;  // a stray byte is dropped
      continue;
    }
    if (!isHiddenControl(c.cp)) {
      out.append(raw.substr(i, c.len));
      ++chars;
    }
    i += c.len;
  }
  // No leading or trailing blanks left by what was removed.
  const auto first = out.find_first_not_of(' ');
  if (first == std::string::npos) return "";
  return out.substr(first, out.find_last_not_of(' ') - first + 1);
}

std::string shown(std::string_view text, std::size_t maxBytes) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const CodePoint c = decode(text, i);
    const std::size_t len = c.len == 0 ? 1 : c.len;
    const std::size_t outLen = c.len == 0 || isHiddenControl(c.cp) ? 1 : c.len;
    if (out.size() + outLen > maxBytes) break;
    if (c.len == 0 || isHiddenControl(c.cp)) out += '?';
    else out.append(text.substr(i, c.len));
    i += len;
  }
  if (i < text.size()) out += "...";
  return out;
}

}  // namespace rover::json
