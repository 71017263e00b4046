#pragma once
// Splits a multipart/form-data body that is on disk: file parts into one file each, streaming
// (fixed-size buffer), so an upload of any size never sits in memory; plain fields into memory,
// each at most MultipartLimits::maxFieldBytes.
#include <cstddef>
#include <string>
#include <vector>

namespace rover::api {

struct MultipartPart {
  std::string name;      // form field name
  std::string filename;  // "" for plain fields
  std::string path;      // file parts: the part's bytes, written under `outDir`
  std::string value;     // plain fields: the value
};

struct MultipartLimits {
  std::size_t maxParts = 16;
  std::size_t maxHeaderBytes = 8 * 1024;  // one part's header block
  std::size_t maxFieldBytes = 64 * 1024;  // one plain field's value
};

// The boundary from a Content-Type header value; "" if absent.
std::string multipartBoundary(const std::string& contentType);
// Throws http::ApiError 400 (field "body") on a malformed body, 413 naming the field for a plain
// field over the limit. On any throw the part files it wrote are removed again; `outDir` itself
// stays the caller's.
std::vector<MultipartPart> splitMultipart(const std::string& bodyFile, const std::string& boundary,
                                          const std::string& outDir,
                                          const MultipartLimits& limits = {});

}  // namespace rover::api
