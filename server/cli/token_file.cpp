#include "server/cli/token_file.hpp"

#include <stdexcept>

#include "server/http/request_origin.hpp"

namespace rover::cli {

std::vector<std::pair<std::string, std::string>> parseTokenFile(std::istream& in) {
  std::vector<std::pair<std::string, std::string>> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    if (line.empty() || line.front() == '#') continue;
    const std::string where = "line " + std::to_string(number) + ": ";
    std::string name, token = line;
    if (const auto colon = line.find(':'); colon != std::string::npos) {
      name = line.substr(0, colon);
      token = line.substr(colon + 1);
      const auto valid = http::validOperatorName(name);
      if (!valid || valid->empty())
        throw std::invalid_argument(where + "the name before ':' must be 1 to " +
                                    std::to_string(http::kMaxOperatorChars) + " printable characters");
      name = *valid;
    }
    if (token.empty()) throw std::invalid_argument(where + "the token is empty");
    for (unsigned char c : token)
      if (c < 0x21 || c > 0x7e) throw std::invalid_argument(where + "a token must be printable ASCII without spaces");
    for (const auto& [n, t] : out)
      if (t == token) throw std::invalid_argument(where + "the same token is given twice");
    if (out.size() == kMaxTokens) throw std::invalid_argument(where + "more than " + std::to_string(kMaxTokens) + " tokens");
    out.emplace_back(std::move(name), std::move(token));
  }
  if (out.empty()) throw std::invalid_argument("no token in the file");
  return out;
}

}  // namespace rover::cli
