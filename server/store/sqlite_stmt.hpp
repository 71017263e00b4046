#pragma once
// Small SQLite helpers shared by the server's database and the study database: a prepared
// statement finalized on scope exit (values only ever bound as parameters) and exec(); a full
// disk or failed write throws StorageFull, anything else std::runtime_error.
#include <sqlite3.h>

#include <stdexcept>
#include <string>

#include "server/store/data_dir.hpp"

namespace rover::store {

// A full disk (SQLITE_FULL), a failed write (SQLITE_IOERR_*) or a file over RLIMIT_FSIZE are
// the disk's fault, not a bug: StorageFull.
inline bool storageFailure(int rc) {
  const int primary = rc & 0xff;
  return primary == SQLITE_FULL || primary == SQLITE_IOERR;
}

[[noreturn]] inline void fail(sqlite3* db, const std::string& what) {
  if (db != nullptr && storageFailure(sqlite3_extended_errcode(db)))
    throw StorageFull("the database cannot be written");
  throw std::runtime_error("database: " + what + ": " +
                           (db != nullptr ? sqlite3_errmsg(db) : "out of memory"));
}

// A prepared statement, finalized on scope exit. Values are only ever bound as parameters.
class Stmt {
 public:
  Stmt(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) fail(db, "prepare");
  }
  ~Stmt() { sqlite3_finalize(stmt_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Stmt& bind(int i, const std::string& s) {
    check(sqlite3_bind_text(stmt_, i, s.data(), static_cast<int>(s.size()), SQLITE_TRANSIENT));
    return *this;
  }
  // Binds NULL for an empty string (unset timestamps).
  Stmt& bindOrNull(int i, const std::string& s) {
    if (s.empty()) {
      check(sqlite3_bind_null(stmt_, i));
      return *this;
    }
    return bind(i, s);
  }
  Stmt& bindInt(int i, long long v) {
    check(sqlite3_bind_int64(stmt_, i, v));
    return *this;
  }
  // Binds NULL for a NaN (a metric without a value).
  Stmt& bindReal(int i, double v) {
    check(v != v ? sqlite3_bind_null(stmt_, i) : sqlite3_bind_double(stmt_, i, v));
    return *this;
  }
  // Clears the bindings' step state for the next row of a prepared insert.
  void reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }

  // Steps once: true if a row is available, false when done; throws on error.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail(db_, "step");
  }
  void run() {
    while (step()) {
    }
  }

  std::string text(int col) const {
    const auto* p = sqlite3_column_text(stmt_, col);
    if (p == nullptr) return {};
    return {reinterpret_cast<const char*>(p), static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col))};
  }
  bool isNull(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  long long integer(int col) const { return sqlite3_column_int64(stmt_, col); }
  double real(int col) const { return sqlite3_column_double(stmt_, col); }
  int columns() const { return sqlite3_column_count(stmt_); }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) fail(db_, "bind");
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

inline void exec(sqlite3* db, const char* sql) {
  char* err = nullptr;
  if (const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &err); rc != SQLITE_OK) {
    if (storageFailure(sqlite3_extended_errcode(db)) || storageFailure(rc)) {
      sqlite3_free(err);
      throw StorageFull("the database cannot be written");
    }
    std::string msg = err != nullptr ? err : sqlite3_errmsg(db);
    sqlite3_free(err);
    throw std::runtime_error("database: " + std::string(sql).substr(0, 60) + ": " + msg);
  }
}

}  // namespace rover::store
