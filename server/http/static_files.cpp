#include "server/http/static_files.hpp"

#include <algorithm>
#include <cctype>
#include <system_error>
#include <utility>

namespace rover::http {

namespace fs = std::filesystem;

StaticFiles::StaticFiles(const std::string& webRoot) {
  if (webRoot.empty()) return;
  std::error_code ec;
  root_ = fs::weakly_canonical(fs::absolute(webRoot, ec), ec);
  if (ec) root_ = fs::absolute(webRoot).lexically_normal();
}

bool StaticFiles::underRoot(const fs::path& canonical) const {
  // Component-wise prefix test: "/srv/web2" is not under "/srv/web".
  auto r = root_.begin();
  auto c = canonical.begin();
  for (; r != root_.end(); ++r, ++c) {
    if (r->empty() && std::next(r) == root_.end()) break;  // root written with a trailing slash
    if (c == canonical.end() || *r != *c) return false;
  }
  return true;
}

std::optional<fs::path> StaticFiles::resolve(const std::string& urlPath) const {
  if (!enabled()) return std::nullopt;
  if (urlPath.find('\0') != std::string::npos) return std::nullopt;
  std::string rel = urlPath;
  while (!rel.empty() && rel.front() == '/') rel.erase(rel.begin());
  if (rel.empty() || rel.back() == '/') rel += "index.html";
  fs::path candidate = fs::path(rel);
  if (candidate.is_absolute()) return std::nullopt;
  for (const auto& part : candidate)
    if (part == "..") return std::nullopt;

  std::error_code ec;
  fs::path full = fs::weakly_canonical(root_ / candidate, ec);
  if (ec || !underRoot(full)) return std::nullopt;
  if (fs::is_directory(full, ec)) {
    full = fs::weakly_canonical(full / "index.html", ec);
    if (ec || !underRoot(full)) return std::nullopt;
  }
  if (!fs::is_regular_file(full, ec)) return std::nullopt;
  return full;
}

Response StaticFiles::serve(const std::string& urlPath) const {
  auto file = resolve(urlPath);
  if (!file) return Response::error(404, "not_found", "no such file: " + urlPath, "path");
  Response r;
  r.status = 200;
  r.file = file->string();
  r.contentType = contentType(*file);
  if (file->filename() == "index.html") r.headers.emplace_back("Cache-Control", "no-cache");
  return r;
}

std::string StaticFiles::contentType(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::pair<const char*, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"},
      {".htm", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".geojson", "application/geo+json"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".jpeg", "image/jpeg"},
      {".gif", "image/gif"},
      {".webp", "image/webp"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".wasm", "application/wasm"},
      {".txt", "text/plain; charset=utf-8"},
      {".md", "text/markdown; charset=utf-8"},
      {".csv", "text/csv; charset=utf-8"},
      {".tif", "image/tiff"},
      {".tiff", "image/tiff"},
      {".woff", "font/woff"},
      {".woff2", "font/woff2"},
  };
  for (const auto& [e, type] : kTypes)
    if (ext == e) return type;
  return "application/octet-stream";
}

}  // namespace rover::http
