#pragma once
// Static files under a web root (the browser front end). Resolution is confined to the root: the
// candidate is canonicalised (weakly_canonical resolves "..", "." and symlinks) and must stay
// under the canonical root, so neither ".." nor a symlink pointing outside can escape it.
#include <filesystem>
#include <optional>
#include <string>

#include "server/http/http_types.hpp"

namespace rover::http {

class StaticFiles {
 public:
  explicit StaticFiles(const std::string& webRoot);  // "" = disabled

  bool enabled() const { return !root_.empty(); }
  // The regular file for a decoded URL path ("/" and directories -> index.html), or nullopt when
  // it does not exist or would leave the root.
  std::optional<std::filesystem::path> resolve(const std::string& urlPath) const;
  // GET/HEAD of `urlPath`: a Response with `file` set (Content-Type by extension, no-cache for
  // index.html), or a 404 JSON error.
  Response serve(const std::string& urlPath) const;

  static std::string contentType(const std::filesystem::path& file);

 private:
  bool underRoot(const std::filesystem::path& canonical) const;
  std::filesystem::path root_;  // canonical
};

}  // namespace rover::http
