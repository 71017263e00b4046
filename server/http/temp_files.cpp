#include "server/http/temp_files.hpp"

#include <unistd.h>
#include <filesystem>
#include <random>
#include <sstream>

namespace rover::http {

namespace fs = std::filesystem;

UploadFiles::UploadFiles(std::string dir) : dir_(std::move(dir)) {
  std::random_device rd;
  salt_ = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
}

std::string UploadFiles::newPath() {
  std::uint64_t n;
  {
    std::lock_guard lock(mutex_);
    n = ++counter_;
  }
  const fs::path dir = dir_.empty() ? fs::temp_directory_path() : fs::path(dir_);
  std::error_code ec;
  fs::create_directories(dir, ec);
  std::ostringstream name;
  name << "upload-" << ::getpid() << '-' << std::hex << salt_ << '-' << std::dec << n << ".part";
  return (dir / name.str()).string();
}

void TempFile::remove() noexcept {
  if (path_.empty()) return;
  std::error_code ec;
  fs::remove(path_, ec);
  path_.clear();
}

}  // namespace rover::http
