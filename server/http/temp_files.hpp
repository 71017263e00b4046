#pragma once
// Streamed request bodies on disk: a unique name for each in the upload folder, and the file a
// session holds until the handler is done with it (the handler moves it away if it keeps it).
#include <cstdint>
#include <mutex>
#include <string>

namespace rover::http {

// Names for streamed bodies, unique across sessions and processes: upload-PID-SALT-N.part.
class UploadFiles {
 public:
  // `dir`: the upload folder ("" = the system temp folder), created on first use.
  explicit UploadFiles(std::string dir);
  std::string newPath();  // thread-safe

 private:
  const std::string dir_;
  std::mutex mutex_;
  std::uint64_t counter_ = 0;
  std::uint64_t salt_ = 0;
};

// One body file a session owns: removed by remove() or at destruction (no error if it is gone).
class TempFile {
 public:
  TempFile() = default;
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() { remove(); }

  void adopt(std::string path) {
    remove();
    path_ = std::move(path);
  }
  // Forgets the path without removing it (the file was never created).
  void release() { path_.clear(); }
  void remove() noexcept;
  const std::string& path() const { return path_; }
  bool empty() const { return path_.empty(); }

 private:
  std::string path_;
};

}  // namespace rover::http
