#include "server/store/data_dir.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "server/store/disk_budget.hpp"

namespace fs = std::filesystem;

namespace rover::store {

namespace {

std::string errnoText(int err) { return std::error_code(err, std::generic_category()).message(); }

// Throws StorageFull for a full disk, else std::runtime_error with `detail` (may name paths: it
// is logged, and the HTTP edge answers 500 without it being a user's fault).
[[noreturn]] void throwWriteError(int err, const std::string& what, const std::string& detail) {
  if (isStorageFullErrno(err)) throw StorageFull("cannot store " + what);
  throw std::runtime_error(detail + ": " + errnoText(err));
}

// Opens `path` read-only and fsyncs it. Returns 0 or the errno of the failure.
int fsyncPath(const fs::path& path, bool directory) {
  int flags = O_RDONLY | O_CLOEXEC;
  if (directory) flags |= O_DIRECTORY;
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) return errno;
  int err = 0;
  if (::fsync(fd) != 0) err = errno;
  ::close(fd);
  return err;
}

// Best effort: some filesystems refuse fsync on a directory (EINVAL); the data is still renamed.
void fsyncDirBestEffort(const fs::path& dir) {
  (void)fsyncPath(dir.empty() ? fs::path(".") : dir, true);
}

// Flushes every regular file under `dir` (throws on failure) and every folder (best effort),
// deepest first, so that after the rename the whole tree is on disk.
void fsyncTree(const fs::path& dir) {
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const auto& entry = *it;
    std::error_code sec;
    if (entry.is_regular_file(sec)) {
      if (const int err = fsyncPath(entry.path(), false); err != 0)
        throwWriteError(err, entry.path().filename().string(), "cannot flush '" + entry.path().string() + "'");
    } else if (entry.is_directory(sec)) {
      fsyncDirBestEffort(entry.path());
    }
  }
  if (ec) throw std::runtime_error("cannot list '" + dir.string() + "': " + ec.message());
  fsyncDirBestEffort(dir);
}

}  // namespace

bool isStorageFullErrno(int err) { return err == ENOSPC || err == EDQUOT || err == EFBIG; }

DataDir::~DataDir() = default;

DataDir::DataDir(std::string root) : root_(std::move(root)), budget_(std::make_unique<DiskBudget>()) {
  if (root_.empty()) throw std::runtime_error("data directory: empty path");
  const fs::path r(root_);
  for (const fs::path& dir : {r, r / "maps", r / "pdms", r / "missions", r / "tmp"}) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec)
      throw std::runtime_error("data directory '" + root_ + "': cannot create '" + dir.string() +
                               "': " + ec.message());
    if (!fs::is_directory(dir, ec))
      throw std::runtime_error("data directory '" + root_ + "': '" + dir.string() +
                               "' exists but is not a folder");
  }
  // Writability probe: create and remove a file in the root (and in tmp/, where uploads go).
  for (const fs::path& dir : {r, r / "tmp"}) {
    const fs::path probe = dir / (".write-probe-" + newId());
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0 && isStorageFullErrno(errno)) {
      startedFull_ = true;  // writable, only full: start, and let each write be refused
      continue;
    }
    if (fd < 0) {
      throw std::runtime_error("data directory '" + root_ + "' is not writable: cannot create '" +
                               probe.string() + "': " + errnoText(errno));
    }
    const bool wrote = ::write(fd, "x", 1) == 1;
    const int writeErr = errno;
    ::close(fd);
    ::unlink(probe.c_str());
    if (!wrote && isStorageFullErrno(writeErr)) {
      startedFull_ = true;
      continue;
    }
    if (!wrote)
      throw std::runtime_error("data directory '" + root_ + "' is not writable: cannot write '" +
                               probe.string() + "': " + errnoText(writeErr));
  }
}

std::string DataDir::databasePath() const { return (fs::path(root_) / "roverplan.db").string(); }
std::string DataDir::mapDir(const std::string& id) const {
  return (fs::path(root_) / "maps" / id).string();
}
std::string DataDir::pdmDir(const std::string& id) const {
  return (fs::path(root_) / "pdms" / id).string();
}
std::string DataDir::missionDir(const std::string& id) const {
  return (fs::path(root_) / "missions" / id).string();
}
std::string DataDir::tmpDir() const { return (fs::path(root_) / "tmp").string(); }

std::string DataDir::newId() {
  // One device per thread: std::random_device is not safe to share between threads.
  thread_local std::random_device rd;
  const std::uint64_t v = (static_cast<std::uint64_t>(rd()) << 32) ^ static_cast<std::uint64_t>(rd());
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string DataDir::stagingDir() const {
  const fs::path tmp(tmpDir());
  std::error_code ec;
  fs::create_directories(tmp, ec);  // in case someone removed it while the server runs
  for (int attempt = 0; attempt < 16; ++attempt) {
    const fs::path dir = tmp / newId();
    if (fs::create_directory(dir, ec)) return dir.string();
    if (ec && isStorageFullErrno(ec.value())) throw StorageFull("cannot create a staging folder");
    if (ec)
      throw std::runtime_error("cannot create staging folder '" + dir.string() +
                               "': " + ec.message());
    // Exists already (an id collision): try another name.
  }
  throw std::runtime_error("cannot create a unique staging folder in '" + tmp.string() + "'");
}

void DataDir::commitDir(const std::string& staged, const std::string& finalDir,
                        const std::optional<DiskCharge>& charge) const {
  std::error_code ec;
  if (!fs::is_directory(staged, ec))
    throw std::runtime_error("commit: staged folder '" + staged + "' does not exist");
  // rename(2) would silently replace an empty target folder, so refuse any existing target first.
  // (Callers commit fresh random ids, so there is no race on the same target in practice.)
  if (fs::exists(fs::symlink_status(finalDir, ec)))
    throw std::runtime_error("commit: target '" + finalDir + "' already exists");
  const fs::path target(finalDir);
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec)
      throw std::runtime_error("commit: cannot create '" + target.parent_path().string() +
                               "': " + ec.message());
  }
  fsyncTree(staged);
  if (charge) budget_->charge(finalDir, charge->use, charge->mapId, bytesUnder(staged), charge->field);
  fs::rename(staged, target, ec);
  if (ec) {
    budget_->release(finalDir);
    if (isStorageFullErrno(ec.value())) throw StorageFull("cannot commit " + target.filename().string());
    throw std::runtime_error("commit: cannot move '" + staged + "' to '" + finalDir + "': " + ec.message());
  }
  // Make the rename itself durable: flush both parent folders.
  fsyncDirBestEffort(target.parent_path());
  fsyncDirBestEffort(fs::path(staged).parent_path());
}

std::optional<std::string> DataDir::readFileUpTo(const std::string& path, std::uint64_t maxBytes, Read how) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  struct stat st {};
  std::optional<std::string> bytes;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && static_cast<std::uint64_t>(st.st_size) <= maxBytes) {
    std::string out(static_cast<std::size_t>(st.st_size), '\0');
    std::size_t got = 0;
    int flags = how == Read::CachedOnly ? RWF_NOWAIT : 0;
    while (got < out.size()) {
      iovec into{out.data() + got, out.size() - got};
      const ssize_t n = ::preadv2(fd, &into, 1, static_cast<off_t>(got), flags);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && flags != 0 && (errno == EOPNOTSUPP || errno == EINVAL || errno == ENOSYS)) {
        flags = 0;  // the filesystem cannot say what is cached: read it plainly
        continue;
      }
      if (n <= 0) break;  // not cached (EAGAIN), an error, or the file shrank: not the whole file
      got += static_cast<std::size_t>(n);
    }
    if (got == out.size()) bytes = std::move(out);
  }
  ::close(fd);
  return bytes;
}

void DataDir::writeFileAtomic(const std::string& path, const std::string& bytes, bool durable) {
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string tmpName = ".";  // hidden, and unique per call
  tmpName += target.filename().string();
  tmpName += ".tmp-";
  tmpName += newId();
  const fs::path tmp = dir / tmpName;

  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0)
    throwWriteError(errno, target.filename().string(),
                    "cannot write '" + path + "': cannot create temporary file '" + tmp.string() + "'");
  auto failWith = [&](const char* what, int err) {
    ::unlink(tmp.c_str());
    throwWriteError(err, target.filename().string(), "cannot write '" + path + "': " + what);
  };

  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      failWith("write", err);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (durable && ::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    failWith("fsync", err);
  }
  if (::close(fd) != 0) failWith("close", errno);
  if (::rename(tmp.c_str(), target.c_str()) != 0) failWith("rename", errno);
  if (durable) fsyncDirBestEffort(dir);
}

void DataDir::remove(const std::string& path) const {
  removeTree(path);
  budget_->release(path);
}

void DataDir::flushFile(const std::string& path) {
  if (const int err = fsyncPath(path, false); err != 0)
    throwWriteError(err, fs::path(path).filename().string(), "cannot flush '" + path + "'");
}

void DataDir::flushDir(const std::string& dir) { fsyncDirBestEffort(dir); }

void DataDir::removeTree(const std::string& path) {
  std::error_code ec;
  fs::remove_all(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory)
    throw std::runtime_error("cannot remove '" + path + "': " + ec.message());
}

void DataDir::cleanTmp() const {
  const fs::path tmp(tmpDir());
  std::error_code ec;
  fs::create_directories(tmp, ec);
  if (ec) throw std::runtime_error("cannot create '" + tmp.string() + "': " + ec.message());
  std::vector<fs::path> entries;
  for (fs::directory_iterator it(tmp, ec), end; !ec && it != end; it.increment(ec))
    entries.push_back(it->path());
  if (ec) throw std::runtime_error("cannot list '" + tmp.string() + "': " + ec.message());
  for (const auto& e : entries) removeTree(e.string());
}

}  // namespace rover::store
