// Small RAII helpers over the SQLite C API for the model store (store.cc): errors as values.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/expected.h"

namespace glimpse::server::sql {

// An SQLite result code as the store's error: busy/locked and full are resource_exhausted, corrupt is
// data_loss, read-only / cannot open / no permission are failed_precondition, the rest internal.
Error SqlError(sqlite3* db, int rc, std::string_view what);

// Runs SQL without results (schema, BEGIN/COMMIT).
Status Exec(sqlite3* db, const char* sql);

// A prepared statement, finalized on scope exit.
class Stmt {
 public:
  Stmt(sqlite3* db, std::string_view sql) : db_(db) {
    rc_ = sqlite3_prepare_v2(db, sql.data(), static_cast<int>(sql.size()), &stmt_, nullptr);
  }
  ~Stmt() { sqlite3_finalize(stmt_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Status prepared() const {
    if (rc_ != SQLITE_OK) return SqlError(db_, rc_, "prepare");
    return {};
  }
  Stmt& bind(int i, std::string_view s) {
    sqlite3_bind_text(stmt_, i, s.data(), static_cast<int>(s.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind(int i, int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  Stmt& bind(int i, double v) {
    sqlite3_bind_double(stmt_, i, v);
    return *this;
  }
  Stmt& bind_null(int i) {
    sqlite3_bind_null(stmt_, i);
    return *this;
  }
  Stmt& bind_blob(int i, std::span<const uint8_t> b) {
    sqlite3_bind_blob64(stmt_, i, b.data(), b.size(), SQLITE_STATIC);
    return *this;
  }
  // true: a row is ready; false: done. Errors (including a failed prepare) as values.
  Expected<bool> step() {
    if (rc_ != SQLITE_OK) return SqlError(db_, rc_, "prepare");
    int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    return SqlError(db_, rc, "step");
  }
  Status run() {
    auto r = step();
    if (!r) return r.error();
    return {};
  }
  int64_t i64(int col) const { return sqlite3_column_int64(stmt_, col); }
  double f64(int col) const { return sqlite3_column_double(stmt_, col); }
  bool null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  std::string text(int col) const {
    auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, col));
    return p ? std::string(p, static_cast<size_t>(sqlite3_column_bytes(stmt_, col))) : std::string();
  }
  std::vector<uint8_t> blob(int col) const {
    auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, col));
    return p ? std::vector<uint8_t>(p, p + sqlite3_column_bytes(stmt_, col)) : std::vector<uint8_t>();
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  int rc_ = SQLITE_OK;
};

// BEGIN IMMEDIATE takes the write lock up front (no upgrade deadlocks between processes); anything
// not committed is rolled back when the transaction goes out of scope.
class WriteTxn {
 public:
  explicit WriteTxn(sqlite3* db) : db_(db), begun_(Exec(db, "BEGIN IMMEDIATE")) {}
  ~WriteTxn() {
    if (begun_.ok() && !committed_) (void)Exec(db_, "ROLLBACK");
  }
  const Status& begun() const { return begun_; }
  Status commit() {
    Status s = Exec(db_, "COMMIT");
    committed_ = s.ok();
    return s;
  }

 private:
  sqlite3* db_;
  Status begun_;
  bool committed_ = false;
};

// The first column of a PRAGMA's first row (0 when it returns none).
Expected<int64_t> PragmaInt(sqlite3* db, const char* pragma);

}  // namespace glimpse::server::sql
