#pragma once
// Who may talk to this server (issue 22, "same-origin by default"): the Host names it answers to,
// and the origins whose pages may change state. Two browser attacks on a server bound to loopback
// without a token:
//   - a page on another origin POSTs a form, a text/plain body or a WebSocket upgrade at it (a
//     "simple" request needs no CORS preflight, so the browser sends it and only hides the answer);
//   - DNS rebinding: evil.example resolves to 127.0.0.1 after the page loads, so its requests reach
//     this server as same-origin, with `Host: evil.example:8080`.
// The first is refused by the Origin check, the second by the Host allow-list. Non-browser clients
// (curl, the CLI, scripts) send no Origin and a loopback or configured Host, and are unaffected.
// Also who may use the API at all: the bearer token of `serve --token`.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/http_types.hpp"

namespace rover::http {

struct OriginPolicy {
  // Host names (no port) answered besides the loopback names (localhost, 127.0.0.0/8, ::1): the
  // bound address when it is not a wildcard, and every --public-name. "*" answers any Host.
  std::vector<std::string> extraHosts;
  // The one foreign origin allowed to change state (--cors), "" for none.
  std::string corsOrigin;
};

// The policy of a server bound to `bindHost` ("0.0.0.0" or "::" for every interface) that also
// answers `publicNames` and lets `corsOrigin` ("" for none) change state.
OriginPolicy originPolicy(const std::string& bindHost, const std::vector<std::string>& publicNames,
                          const std::string& corsOrigin);

// The host part of a Host header value ("Example.org:8080" -> "example.org", "[::1]:80" -> "::1"),
// lower-cased; nullopt when the value is malformed (empty, a bad port, spaces, a userinfo '@').
std::optional<std::string> hostName(std::string_view hostHeader);

// Whether a request with this Host header is for this server.
bool hostAllowed(const OriginPolicy& policy, std::string_view hostHeader);

// Whether a state-changing request (or WebSocket upgrade) with these headers comes from a page of a
// foreign origin: an Origin header that is neither this server's own (scheme://Host) nor the CORS
// origin ("null" included, as sandboxed frames and file: pages send it), or, without an Origin, a
// browser's `Sec-Fetch-Site: cross-site`/`same-site`.
bool foreignOrigin(const OriginPolicy& policy, std::string_view origin, std::string_view secFetchSite,
                   std::string_view hostHeader);

// The answer for a request that is not ours to serve, checked before anything else (even a CORS
// preflight); nullopt when it may go on:
//   400 bad_request without a Host on HTTP/1.1 (RFC 9112 §3.2; an HTTP/1.0 tool may omit it, and
//       no browser does, so its absence opens no rebinding);
//   421 misdirected_request for a Host this server does not answer to (DNS rebinding);
//   403 foreign_origin for a `stateChanging` request (not GET/HEAD/OPTIONS, or a WebSocket
//       upgrade) from a foreign page.
std::optional<Response> refuseByOrigin(const OriginPolicy& policy, const Request& req, unsigned httpVersion,
                                       bool stateChanging);

// Whether `req` presents `token`: "Authorization: Bearer TOKEN", or with `allowQueryToken` (a
// WebSocket upgrade: browsers cannot set its headers) ?token=TOKEN. Compared in constant time.
bool bearerAuthorized(const Request& req, const std::string& token, bool allowQueryToken);
// The same against several (name, token) pairs: the name of the one presented, nullopt when none
// matches. Every token is compared (in constant time), so the time says nothing of which matched.
std::optional<std::string> bearerName(const Request& req,
                                      const std::vector<std::pair<std::string, std::string>>& tokens,
                                      bool allowQueryToken);
// The X-Operator header (issue 26): who a client without a named token says it is. At most
// kMaxOperatorChars characters of printable UTF-8 (no control characters); "" when absent;
// nullopt when invalid (answered 400 naming the header).
constexpr std::size_t kMaxOperatorChars = 40;
std::optional<std::string> validOperatorName(const std::string& value);
// 401 unauthorized with WWW-Authenticate: Bearer.
Response unauthorized();

}  // namespace rover::http
