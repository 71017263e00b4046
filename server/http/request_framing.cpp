#include "server/http/request_framing.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <map>
#include <string>
#include <string_view>

namespace rover::http {

namespace bhttp = boost::beast::http;

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// %XX decoding; '+' is a space in query strings only. False on a malformed escape.
bool percentDecode(std::string_view in, bool plusIsSpace, std::string& out) {
  out.clear();
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const char c = in[i];
    if (c == '%') {
      if (i + 2 >= in.size()) return false;
      const int hi = hexValue(in[i + 1]);
      const int lo = hexValue(in[i + 2]);
      if (hi < 0 || lo < 0) return false;
      out.push_back(static_cast<char>(hi * 16 + lo));
      i += 2;
    } else if (c == '+' && plusIsSpace) {
      out.push_back(' ');
    } else {
      out.push_back(c);
    }
  }
  return true;
}

FramingError refuse(std::string message, std::string field) {
  return FramingError{400, "bad_framing", std::move(message), std::move(field)};
}

}  // namespace

void configureHeaderParser(bhttp::request_parser<bhttp::empty_body>& p,
                           std::uint32_t maxHeaderBytes) {
  p.header_limit(maxHeaderBytes);
  // max, not none: Beast 1.74 compares a Content-Length against an empty optional as "over the
  // limit"; the route's own limit replaces this once the header is known.
  p.body_limit(std::numeric_limits<std::uint64_t>::max());
  p.eager(false);  // stop after the header: the body type depends on the route
}

bool parseTarget(std::string_view target, std::string& path,
                 std::map<std::string, std::string>& query, std::string* repeated) {
  if (target.empty() || target.front() != '/') return false;
  const std::size_t hash = target.find('#');
  if (hash != std::string_view::npos) target = target.substr(0, hash);
  const std::size_t q = target.find('?');
  const std::string_view rawPath = target.substr(0, q);
  if (!percentDecode(rawPath, false, path)) return false;
  if (path.find('\0') != std::string::npos) return false;
  std::size_t start = 0;
  while (start <= path.size()) {
    std::size_t slash = path.find('/', start);
    if (slash == std::string::npos) slash = path.size();
    if (path.compare(start, slash - start, "..") == 0) return false;
    start = slash + 1;
  }
  if (q == std::string_view::npos) return true;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    std::size_t amp = rest.find('&');
    std::string_view pair = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
    if (pair.empty()) continue;
    const std::size_t eq = pair.find('=');
    std::string key, value;
    if (!percentDecode(pair.substr(0, eq), true, key)) return false;
    if (eq != std::string_view::npos && !percentDecode(pair.substr(eq + 1), true, value))
      return false;
    if (key.find('\0') != std::string::npos || value.find('\0') != std::string::npos) return false;
    // A parameter given twice has no one meaning (first or last?): refused, not guessed.
    if (query.count(key)) {
      if (repeated) *repeated = key.size() <= 64 ? key : "query";
      return false;
    }
    query.emplace(std::move(key), std::move(value));
  }
  return true;
}

std::optional<FramingError> checkFraming(const bhttp::request_header<>& header) {
  // Every Transfer-Encoding field line, as one comma-separated list of codings; every
  // Content-Length line.
  std::size_t codings = 0;
  bool chunkedOnly = true;
  std::size_t teLines = 0;
  std::size_t clLines = 0;
  bool clList = false;
  for (const auto& f : header) {
    if (f.name() == bhttp::field::content_length) {
      ++clLines;
      const auto v = f.value();
      if (std::string_view(v.data(), v.size()).find(',') != std::string_view::npos) clList = true;
      continue;
    }
    if (f.name() != bhttp::field::transfer_encoding) continue;
    ++teLines;
    const auto v = f.value();
    std::string_view rest(v.data(), v.size());
    for (;;) {
      const std::size_t comma = rest.find(',');
      const std::string_view item = trim(rest.substr(0, comma));
      if (!item.empty()) {
        ++codings;
        if (!iequals(item, "chunked")) chunkedOnly = false;
      }
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
  }

  if (teLines > 0) {
    if (clLines > 0)
      return refuse("Transfer-Encoding and Content-Length together are ambiguous framing",
                    "transfer-encoding");
    if (header.version() < 11)
      return refuse("Transfer-Encoding is not allowed on an HTTP/1.0 request", "transfer-encoding");
    if (codings != 1 || !chunkedOnly)
      return refuse("Transfer-Encoding must be exactly \"chunked\" (no other coding is supported)",
                    "transfer-encoding");
  }
  if (clLines > 1 || clList) return refuse("more than one Content-Length", "content-length");
  return std::nullopt;
}

std::optional<FramingError> checkBodyLength(const boost::optional<std::uint64_t>& contentLength,
                                            std::uint64_t limit) {
  if (!contentLength || *contentLength <= limit) return std::nullopt;
  return FramingError{413, "payload_too_large",
                      "body of " + std::to_string(*contentLength) +
                          " bytes exceeds the limit of " + std::to_string(limit),
                      "body"};
}

}  // namespace rover::http
