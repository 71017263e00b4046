#include "server/http/router.hpp"

#include <algorithm>

namespace rover::http {

namespace {

// "/a/b/" -> {"a", "b", ""}; "/" -> {""}. The leading slash is dropped, empty segments are kept
// so "/maps/" never matches "/maps/{id}" (a capture needs a non-empty segment).
std::vector<std::string> splitSegments(const std::string& path) {
  std::vector<std::string> out;
  std::size_t start = path.empty() || path[0] != '/' ? 0 : 1;
  for (;;) {
    std::size_t slash = path.find('/', start);
    if (slash == std::string::npos) {
      out.push_back(path.substr(start));
      return out;
    }
    out.push_back(path.substr(start, slash - start));
    start = slash + 1;
  }
}

bool isCapture(const std::string& seg) {
  return seg.size() >= 3 && seg.front() == '{' && seg.back() == '}';
}

// Matches whole segments. On success fills `params` and `literalMask` ('1' literal, '0' capture)
// whose lexicographic order ranks specificity.
bool matchPattern(const std::vector<std::string>& pat, const std::vector<std::string>& path,
                  std::map<std::string, std::string>& params, std::string& literalMask) {
  if (pat.size() != path.size()) return false;
  params.clear();
  literalMask.clear();
  for (std::size_t i = 0; i < pat.size(); ++i) {
    if (isCapture(pat[i])) {
      if (path[i].empty()) return false;
      params[pat[i].substr(1, pat[i].size() - 2)] = path[i];
      literalMask.push_back('0');
    } else {
      if (pat[i] != path[i]) return false;
      literalMask.push_back('1');
    }
  }
  return true;
}

}  // namespace

void Router::add(const std::string& method, const std::string& pattern, Handler h, RouteOptions o) {
  Route r;
  r.method = method;
  r.pattern = pattern;
  r.handler = std::move(h);
  r.options = std::move(o);
  routes_.push_back(std::move(r));
  segments_.push_back(splitSegments(pattern));
}

void Router::addWebSocket(const std::string& pattern, WsHandler h, RouteOptions o) {
  Route r;
  r.method = "WS";
  r.pattern = pattern;
  r.wsHandler = std::move(h);
  r.options = std::move(o);
  routes_.push_back(std::move(r));
  segments_.push_back(splitSegments(pattern));
}

Router::Match Router::match(const std::string& method, const std::string& path,
                            bool websocket) const {
  const std::vector<std::string> segs = splitSegments(path);
  Match best;
  std::string bestMask;
  int bestRank = -1;  // 1: a WS route for an upgrade, 0: a plain route
  std::map<std::string, std::string> params;
  std::string mask;
  for (std::size_t i = 0; i < routes_.size(); ++i) {
    const Route& r = routes_[i];
    if (!matchPattern(segments_[i], segs, params, mask)) continue;
    int rank = -1;
    if (r.method == "WS") {
      if (websocket && method == "GET") rank = 1;
    } else if (r.method == method) {
      rank = 0;
    }
    if (rank < 0) {
      best.pathKnown = true;
      continue;
    }
    if (rank > bestRank || (rank == bestRank && mask > bestMask)) {
      best.route = &r;
      best.params = params;
      bestMask = mask;
      bestRank = rank;
    }
  }
  if (best.route) best.pathKnown = false;
  return best;
}

std::vector<std::string> Router::allowedMethods(const std::string& path) const {
  const std::vector<std::string> segs = splitSegments(path);
  std::vector<std::string> out;
  std::map<std::string, std::string> params;
  std::string mask;
  for (std::size_t i = 0; i < routes_.size(); ++i) {
    const Route& r = routes_[i];
    if (!matchPattern(segments_[i], segs, params, mask)) continue;
    out.push_back(r.method == "WS" ? "GET" : r.method);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace rover::http
