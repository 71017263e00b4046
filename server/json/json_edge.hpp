#pragma once
// The one way the server reads an untrusted JSON body (issue 14): size and nesting depth are checked
// before any DOM exists. nlohmann's parser itself is iterative, but copying a parsed value and
// dump() recurse once per nesting level, so a 70 000-deep array overflowed the stack in the
// handler. The depth check is a single byte scan (no recursion, no allocation) done first.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace rover::json {

struct JsonLimits {
  std::size_t maxBytes = std::size_t{1} << 20;  // larger bodies: 413 payload_too_large
  int maxDepth = 64;                            // deeper nesting of [ and {: 400 too_deep
};

// A mission request is a few KB (64 rovers, ~40 parameters); 64 KiB also bounds what every listed
// mission carries in its stored spec.
inline constexpr JsonLimits kMissionJsonLimits{std::size_t{64} << 10, 64};
// A PDM holds at most pdm::kMaxComponents (256) Gaussians of ~120 bytes; 1 MiB leaves room for
// pretty-printed bodies.
inline constexpr JsonLimits kPdmJsonLimits{std::size_t{1} << 20, 64};

// The deepest nesting of arrays/objects in `text`, scanning outside strings only; stops counting
// once `stopAt` is exceeded. Does not validate the JSON.
int jsonNestingDepth(std::string_view text, int stopAt);

// Parses a request body under `limits`. Throws http::ApiError with field "body":
// 400 too_deep, 413 payload_too_large, 400 bad_json (not JSON, or not an object when
// `requireObject`, or an object that names a key twice: RFC 8259 leaves the meaning of duplicate
// names open, and nlohmann keeps the last one, so `{"rovers":1,"rovers":64}` would be read
// differently by us and by a proxy or validator that keeps the first).
nlohmann::json parseJsonLimited(std::string_view text, const JsonLimits& limits, bool requireObject = true);

// The one name rule, for every named object (maps, PDMs, zones, missions, studies and their worlds
// and configurations): valid UTF-8 of at most kMaxNameChars characters (code points), none of them a
// hidden control (isHiddenControl). nameProblem says what is wrong ("" when nothing is), for
// callers with their own error type; checkName throws http::ApiError 400 invalid_field naming
// `field`.
inline constexpr std::size_t kMaxNameChars = 200;
std::string nameProblem(std::string_view name);
void checkName(std::string_view name, const std::string& field);
// C0/C1 controls, DEL, zero-width and bidi marks/overrides/isolates, U+2028/2029, U+FEFF.
bool isHiddenControl(std::uint32_t codePoint);
// A name made from untrusted text (a file or zip member name): invalid bytes and hidden controls
// dropped, cut at `maxChars` code points, blanks trimmed; passes checkName. May be "".
std::string cleanName(std::string_view raw, std::size_t maxChars = kMaxNameChars);
// Untrusted text echoed in an error message or field: at most `maxBytes` bytes, cut at a character
// boundary and followed by "..." when cut; invalid bytes and hidden controls shown as '?'.
std::string shown(std::string_view text, std::size_t maxBytes = 64);

}  // namespace rover::json
