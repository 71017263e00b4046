#include "server/http/request_framing.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
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

}  // namespace rover::http
