#include "server/api/multipart.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "server/http/http_types.hpp"

namespace rover::api {

namespace {

[[noreturn]] void bad(const std::string& why) {
  throw http::ApiError(400, "bad_multipart", "malformed multipart body: " + why, "body");
}

[[noreturn]] void cannotStore() {
  throw http::ApiError(507, "insufficient_storage", "cannot store an uploaded part (disk full?)", "body");
}

std::string paramOf(const std::string& header, const std::string& key) {
  // key="value" or key=value inside a header value.
  auto pos = header.find(key + "=");
  while (pos != std::string::npos && pos > 0 && std::isalnum(static_cast<unsigned char>(header[pos - 1])))
    pos = header.find(key + "=", pos + 1);
  if (pos == std::string::npos) return "";
  pos += key.size() + 1;
  if (pos < header.size() && header[pos] == '"') {
    auto end = header.find('"', pos + 1);
    return end == std::string::npos ? "" : header.substr(pos + 1, end - pos - 1);
  }
  auto end = header.find_first_of("; \r\n", pos);
  return header.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
}

// Removes the part files written so far unless the split succeeded.
struct WrittenParts {
  std::vector<std::string> paths;
  bool keep = false;
  ~WrittenParts() {
    if (keep) return;
    for (const auto& p : paths) {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
  }
};

}  // namespace

std::string multipartBoundary(const std::string& contentType) {
  std::string lower = contentType;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (lower.rfind("multipart/form-data", 0) != 0) return "";
  auto pos = lower.find("boundary=");
  if (pos == std::string::npos) return "";
  return paramOf(contentType.substr(pos), "boundary");
}

std::vector<MultipartPart> splitMultipart(const std::string& bodyFile, const std::string& boundary,
                                          const std::string& outDir, const MultipartLimits& limits) {
  if (boundary.empty() || boundary.size() > 200) bad("missing or overlong boundary");
  std::ifstream in(bodyFile, std::ios::binary);
  if (!in) bad("cannot read the body");
  const std::string delim = "\r\n--" + boundary;
  // Prepend CRLF so the first boundary looks like every other one.
  std::string buf = "\r\n";
  std::vector<MultipartPart> parts;
  WrittenParts written;
  std::ofstream out;
  enum { Preamble, Headers, Body, Done } state = Preamble;
  std::vector<char> chunk(1 << 20);
  bool eof = false;
  auto readMore = [&] {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    buf.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    eof = !in;
  };
  // Body bytes of the current part: to its file, or to its in-memory value (bounded).
  auto emit = [&](const char* data, std::size_t n) {
    MultipartPart& p = parts.back();
    if (!p.filename.empty()) {
      out.write(data, static_cast<std::streamsize>(n));
      return;
    }
    if (p.value.size() + n > limits.maxFieldBytes)
      throw http::ApiError(413, "field_too_large",
                           "form field '" + p.name + "' exceeds " +
                               std::to_string(limits.maxFieldBytes) + " bytes",
                           p.name.empty() ? "body" : p.name);
    p.value.append(data, n);
  };
  while (state != Done) {
    if (!eof && buf.size() < (1u << 20)) readMore();
    if (state == Preamble || state == Body) {
      auto pos = buf.find(delim);
      if (pos == std::string::npos) {
        if (eof) bad("no closing boundary");
        // Keep the tail that could start a delimiter; pass on the rest of a body part.
        std::size_t keep = std::min(buf.size(), delim.size());
        if (state == Body) emit(buf.data(), buf.size() - keep);
        buf.erase(0, buf.size() - keep);
        continue;
      }
      if (state == Body) {
        emit(buf.data(), pos);
        if (out.is_open()) {
          out.close();
          if (!out) cannotStore();
        }
      }
      buf.erase(0, pos + delim.size());
      while (buf.size() < 2 && !eof) readMore();
      if (buf.rfind("--", 0) == 0) {
        state = Done;
        break;
      }
      if (buf.rfind("\r\n", 0) != 0) bad("boundary not followed by CRLF");
      buf.erase(0, 2);
      state = Headers;
    }
    if (state == Headers) {
      auto end = buf.find("\r\n\r\n");
      if (end == std::string::npos || end > limits.maxHeaderBytes) {
        if (eof || buf.size() > limits.maxHeaderBytes)
          bad("part headers over " + std::to_string(limits.maxHeaderBytes) + " bytes or cut off");
        continue;
      }
      const std::string headers = buf.substr(0, end);
      buf.erase(0, end + 4);
      std::string disposition;
      std::size_t start = 0;
      while (start < headers.size()) {
        auto lineEnd = headers.find("\r\n", start);
        std::string line = headers.substr(start, lineEnd == std::string::npos ? std::string::npos : lineEnd - start);
        std::string lower = line;
        std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
        if (lower.rfind("content-disposition:", 0) == 0) disposition = line;
        if (lineEnd == std::string::npos) break;
        start = lineEnd + 2;
      }
      if (parts.size() >= limits.maxParts) bad("more than " + std::to_string(limits.maxParts) + " parts");
      MultipartPart p;
      p.name = paramOf(disposition, "name");
      p.filename = paramOf(disposition, "filename");
      if (!p.filename.empty()) {
        p.path = outDir + "/part" + std::to_string(parts.size());
        written.paths.push_back(p.path);
        out.open(p.path, std::ios::binary | std::ios::trunc);
        if (!out) cannotStore();
      }
      parts.push_back(std::move(p));
      state = Body;
    }
  }
  written.keep = true;
  return parts;
}

}  // namespace rover::api
