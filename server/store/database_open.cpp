#include "server/store/database.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <stdexcept>

#include "server/store/data_dir.hpp"
#include "server/store/database_schema.hpp"
#include "server/store/sqlite_stmt.hpp"

// Opening the server database, and the disk reserves that let final statuses and deletes commit
// on a full disk (its rows are database.cpp's, its schema database_schema.cpp's).
//
// Durability choice: journal_mode=WAL with synchronous=NORMAL. Every write (database.cpp) is a single
// statement, i.e. one implicit transaction. In WAL mode a transaction is committed once its frames
// are appended to the -wal file with write(); with synchronous=NORMAL SQLite does not fsync at
// every commit, only at checkpoints. The data written by write() lives in the kernel's page cache,
// which survives the death of the process (crash, abort, kill -9): the next open replays the WAL.
// So a committed row is never lost to a process crash. Only a power loss / kernel panic can roll
// back the last few transactions (never corrupt the database) — an acceptable trade for a planning
// server whose missions are marked "interrupted" at restart anyway. Use synchronous=FULL if
// power-loss durability of the very last commit ever matters.

namespace rover::store {

Database::Database(const std::string& path) {
  if (!path.empty() && path != ":memory:" && path.rfind("file:", 0) != 0) {
    statusReserve_ = {path + ".reserve-status", kStatusReserveBytes};
    deleteReserve_ = {path + ".reserve-delete", kDeleteReserveBytes};
  }
  try {
    open(path, false);
  } catch (const StorageFull&) {
    // A restart with a full disk: no room for the WAL index (-shm). Exclusive locking keeps it in
    // the process's memory, so reads work and the reserves stay for deletes; failing that, the
    // reserves give SQLite the room.
    try {
      open(path, true);
    } catch (const StorageFull&) {
      if (!release(deleteReserve_) && !release(statusReserve_)) throw;
      open(path, false);
    }
  }
  ensureReserves();
}

bool Database::release(Reserve& r) {
  if (r.path.empty()) return false;
  r.held = false;
  return ::unlink(r.path.c_str()) == 0;
}

void Database::ensureReserves() {
  for (Reserve* r : {&deleteReserve_, &statusReserve_}) {
    if (r->held || r->path.empty()) continue;
    const int fd = ::open(r->path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
    if (fd < 0) return;
    // Allocated blocks, not a sparse file: the point is that the space is really taken.
    const bool ok = ::posix_fallocate(fd, 0, r->bytes) == 0;
    ::close(fd);
    if (!ok) {
      ::unlink(r->path.c_str());
      return;
    }
    r->held = true;
  }
}

void Database::open(const std::string& path, bool exclusive) {
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX;
  if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    std::string msg = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw std::runtime_error("database: cannot open '" + path + "': " + msg);
  }
  try {
    sqlite3_extended_result_codes(db_, 1);
    exec(db_, "PRAGMA busy_timeout=5000");
    if (exclusive) exec(db_, "PRAGMA locking_mode=EXCLUSIVE");
    {
      Stmt s(db_, "PRAGMA journal_mode=WAL");
      const std::string mode = s.step() ? s.text(0) : std::string();
      // An in-memory database (":memory:") reports "memory"; a file must really be in WAL mode.
      if (mode != "wal" && mode != "memory")
        throw std::runtime_error("database: cannot enable WAL on '" + path + "' (journal mode " +
                                 mode + ")");
    }
    exec(db_, "PRAGMA synchronous=NORMAL");
    exec(db_, "PRAGMA foreign_keys=ON");
    migrateSchema(db_, path);
  } catch (...) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw;
  }
}

Database::~Database() {
  if (db_ != nullptr) sqlite3_close_v2(db_);
}

}  // namespace rover::store
