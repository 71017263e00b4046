#include "server/json/json_edge.hpp"
#include "server/http/request_origin.hpp"

#include <algorithm>
#include <cctype>

namespace rover::http {

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool allDigits(std::string_view s) {
  return !s.empty() && s.size() <= 5 && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

// 127.0.0.0/8 written as a dotted quad: the whole block is loopback.
bool loopbackV4(std::string_view host) {
  if (host.rfind("127.", 0) != 0) return false;
  int dots = 0;
  for (char c : host) {
    if (c == '.') ++dots;
    else if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return dots == 3;
}

// Time depends on the secret's length only, not on where the strings differ.
bool constantTimeEquals(const std::string& presented, const std::string& secret) {
  unsigned char diff = presented.size() == secret.size() ? 0 : 1;
  for (std::size_t i = 0; i < secret.size(); ++i) {
    const unsigned char p = i < presented.size() ? static_cast<unsigned char>(presented[i]) : 0;
    diff |= static_cast<unsigned char>(p ^ static_cast<unsigned char>(secret[i]));
  }
  volatile unsigned char result = diff;
  return result == 0;
}

}  // namespace

OriginPolicy originPolicy(const std::string& bindHost, const std::vector<std::string>& publicNames,
                          const std::string& corsOrigin) {
  OriginPolicy p{publicNames, corsOrigin};
  // A wildcard bind names no host; a named one (an interface address or name) is one of ours.
  if (!bindHost.empty() && bindHost != "0.0.0.0" && bindHost != "::" && bindHost != "[::]")
    p.extraHosts.push_back(bindHost);
  return p;
}

std::optional<std::string> hostName(std::string_view value) {
  while (!value.empty() && (value.back() == ' ' || value.back() == '\t')) value.remove_suffix(1);
  while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
  if (value.empty() || value.size() > 255) return std::nullopt;
  std::string_view host = value;
  if (value.front() == '[') {  // an IPv6 literal, port optional
    const std::size_t close = value.find(']');
    if (close == std::string_view::npos) return std::nullopt;
    host = value.substr(1, close - 1);
    const std::string_view rest = value.substr(close + 1);
    if (!rest.empty() && (rest.front() != ':' || !allDigits(rest.substr(1)))) return std::nullopt;
  } else if (const std::size_t colon = value.find(':'); colon != std::string_view::npos) {
    host = value.substr(0, colon);
    if (!allDigits(value.substr(colon + 1))) return std::nullopt;
  }
  if (host.empty()) return std::nullopt;
  for (unsigned char c : host)
    if (!(std::isalnum(c) || c == '.' || c == '-' || c == '_' || c == ':')) return std::nullopt;
  std::string name = lower(host);
  if (name.back() == '.') name.pop_back();  // "localhost." is "localhost"
  return name;
}

bool hostAllowed(const OriginPolicy& policy, std::string_view hostHeader) {
  const std::optional<std::string> name = hostName(hostHeader);
  if (!name) return false;
  if (*name == "localhost" || *name == "::1" || loopbackV4(*name)) return true;
  return std::any_of(policy.extraHosts.begin(), policy.extraHosts.end(),
                     [&](const std::string& h) { return h == "*" || lower(h) == *name; });
}

bool foreignOrigin(const OriginPolicy& policy, std::string_view origin, std::string_view secFetchSite,
                   std::string_view hostHeader) {
  if (origin.empty()) {
    const std::string site = lower(secFetchSite);
    return site == "cross-site" || site == "same-site";
  }
  if (!policy.corsOrigin.empty() && origin == policy.corsOrigin) return false;
  const std::string own = lower(hostHeader);
  const std::string o = lower(origin);
  return o != "http://" + own && o != "https://" + own;
}

std::optional<Response> refuseByOrigin(const OriginPolicy& policy, const Request& req, unsigned httpVersion,
                                       bool stateChanging) {
  const std::string host = req.header("host");
  if (host.empty() && httpVersion >= 11)
    return Response::error(400, "bad_request", "the request has no Host header", "host");
  if (!host.empty() && !hostAllowed(policy, host))
    return Response::error(421, "misdirected_request",
                           "this server does not answer to that Host name (start it with --public-name NAME to add one)",
                           "host");
  if (stateChanging && foreignOrigin(policy, req.header("origin"), req.header("sec-fetch-site"), host))
    return Response::error(403, "foreign_origin",
                           "state-changing requests and live streams are refused from another site's page "
                           "(start the server with --cors ORIGIN to allow one)",
                           "origin");
  return std::nullopt;
}

namespace {
// The token a request presents: "Authorization: Bearer T", or ?token=T on an upgrade.
std::optional<std::string> presentedToken(const Request& req, bool allowQueryToken) {
  std::string presented;
  bool found = false;
  const std::string h = req.header("authorization");
  if (h.size() > 7 && lower(h.substr(0, 7)) == "bearer ") {
    presented = h.substr(7);
    while (!presented.empty() && (presented.back() == ' ' || presented.back() == '\t')) presented.pop_back();
    while (!presented.empty() && presented.front() == ' ') presented.erase(presented.begin());
    found = true;
  }
  if (!found && allowQueryToken) {
    auto it = req.query.find("token");
    if (it != req.query.end()) {
      presented = it->second;
      found = true;
    }
  }
  if (!found) return std::nullopt;
  return presented;
}
}  // namespace

bool bearerAuthorized(const Request& req, const std::string& token, bool allowQueryToken) {
  const auto presented = presentedToken(req, allowQueryToken);
  return presented && constantTimeEquals(*presented, token);
}

std::optional<std::string> bearerName(const Request& req,
                                      const std::vector<std::pair<std::string, std::string>>& tokens,
                                      bool allowQueryToken) {
  const auto presented = presentedToken(req, allowQueryToken);
  if (!presented) return std::nullopt;
  std::optional<std::string> name;
  for (const auto& [who, token] : tokens)
    if (constantTimeEquals(*presented, token) && !name) name = who;
  return name;
}

std::optional<std::string> validOperatorName(const std::string& value) {
  std::size_t chars = 0;
  for (std::size_t i = 0; i < value.size();) {
    const auto c = static_cast<unsigned char>(value[i]);
    std::size_t len = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    if (len == 0 || i + len > value.size()) return std::nullopt;
    if (len == 1 && (c < 0x20 || c == 0x7f)) return std::nullopt;
    for (std::size_t k = 1; k < len; ++k)
      if ((static_cast<unsigned char>(value[i + k]) & 0xc0) != 0x80) return std::nullopt;
    // C1 controls, zero-width and text-direction marks are refused as in every other name
    // (json::isHiddenControl): a name must not show as something it is not.
    std::uint32_t cp = len == 1 ? c : c & (0x7f >> len);
    for (std::size_t k = 1; k < len; ++k) cp = (cp << 6) | (static_cast<unsigned char>(value[i + k]) & 0x3f);
    if (rover::json::isHiddenControl(cp)) return std::nullopt;
    i += len;
    if (++chars > kMaxOperatorChars) return std::nullopt;
  }
  std::string out = value;
  while (!out.empty() && out.back() == ' ') out.pop_back();
  while (!out.empty() && out.front() == ' ') out.erase(out.begin());
  return out;
}

Response unauthorized() {
  Response r = Response::error(401, "unauthorized", "missing or invalid bearer token", "authorization");
  r.headers.emplace_back("WWW-Authenticate", "Bearer");
  return r;
}

}  // namespace rover::http
