#pragma once
// How a request's bytes are framed, checked before anything routes it (RFC 9112 §6). Pure
// functions, shared by HttpSession and the fuzz harness (tests/fuzz/fuzz_http_request.cpp), so the
// harness exercises exactly the parser configuration and the checks the server runs.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/parser.hpp>

namespace rover::http {

// A request the server answers with an error and then closes the connection: after a framing
// error the rest of the bytes cannot be trusted to start a new request.
struct FramingError {
  int status = 400;
  std::string code;
  std::string message;
  std::string field;  // the offending header, lower-case
};

// The header parser as the session configures it: `maxHeaderBytes` for the request line and
// header fields, no body limit yet (the route's limit is applied once the header is known).
void configureHeaderParser(boost::beast::http::request_parser<boost::beast::http::empty_body>& p,
                           std::uint32_t maxHeaderBytes);

// Checks the framing of a parsed request header:
//  - Transfer-Encoding, if present, must be exactly one coding, "chunked" (no other coding is
//    implemented; "gzip" or "chunked, identity" would leave the body's end unknown, and a body
//    parsed as the next request is request smuggling);
//  - Transfer-Encoding and Content-Length together are refused (§6.1), as is Transfer-Encoding
//    on an HTTP/1.0 request;
//  - Content-Length must be one field with one value (duplicates, even equal ones, are refused).
std::optional<FramingError> checkFraming(
    const boost::beast::http::request_header<>& header);

// A declared Content-Length over the route's body limit: 413 before any body parser exists. Beast's
// string_body reserves the declared length up front, so the check must come first, not from the
// body parser's own limit.
std::optional<FramingError> checkBodyLength(const boost::optional<std::uint64_t>& contentLength,
                                            std::uint64_t limit);

// Splits an origin-form request target into a percent-decoded path and query ('+' is a space in
// the query only). False (-> 400) on a malformed target or escape, a NUL byte, a ".." segment, or
// a query parameter given twice (then named in `repeated`, when given).
bool parseTarget(std::string_view target, std::string& path,
                 std::map<std::string, std::string>& query, std::string* repeated = nullptr);

}  // namespace rover::http
