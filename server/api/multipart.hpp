#pragma once
// Splits a multipart/form-data body that is on disk into one file per part, streaming (fixed-size
// buffer), so an upload of any size never sits in memory.
#include <string>
#include <vector>

namespace rover::api {

struct MultipartPart {
  std::string name;      // form field name
  std::string filename;  // "" for plain fields
  std::string path;      // the part's bytes, written under `outDir`
};

// The boundary from a Content-Type header value; "" if absent.
std::string multipartBoundary(const std::string& contentType);
// Throws http::ApiError 400 (field "body") on a malformed body.
std::vector<MultipartPart> splitMultipart(const std::string& bodyFile, const std::string& boundary,
                                          const std::string& outDir);

}  // namespace rover::api
