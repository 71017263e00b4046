#pragma once
// `serve --token-file F` (issue 26): one token per line, `token` or `name:token` (the operator's
// name that events and history then show for that token's requests). Blank lines and lines
// starting with '#' are skipped; trailing spaces/CR are trimmed. A token is printable ASCII
// without spaces; a name is at most 40 printable characters without ':' (it ends at the first
// ':'). At most kMaxTokens lines of tokens. Throws std::invalid_argument naming the line.
#include <istream>
#include <string>
#include <utility>
#include <vector>

namespace rover::cli {

inline constexpr std::size_t kMaxTokens = 256;

// (name, token) pairs in file order; name "" for a plain `token` line.
std::vector<std::pair<std::string, std::string>> parseTokenFile(std::istream& in);

}  // namespace rover::cli
