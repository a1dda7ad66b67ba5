#include "sqlite.h"

namespace glimpse::server::sql {

Error SqlError(sqlite3* db, int rc, std::string_view what) {
  std::string message = std::string(what) + ": " + (db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
  switch (rc & 0xff) {
    case SQLITE_BUSY:
    case SQLITE_LOCKED: return resource_exhausted("model store busy: " + message);
    case SQLITE_FULL: return resource_exhausted("model store full: " + message);
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB: return data_loss("model store corrupt: " + message);
    case SQLITE_READONLY:
    case SQLITE_CANTOPEN:
    case SQLITE_PERM: return failed_precondition("model store not writable: " + message);
    default: return internal_error("model store: " + message);
  }
}

Status Exec(sqlite3* db, const char* sql) {
  char* msg = nullptr;
  int rc = sqlite3_exec(db, sql, nullptr, nullptr, &msg);
  if (rc == SQLITE_OK) return {};
  std::string what = msg ? msg : sqlite3_errstr(rc);
  sqlite3_free(msg);
  return SqlError(nullptr, rc, what);
}

Expected<int64_t> PragmaInt(sqlite3* db, const char* pragma) {
  Stmt s(db, pragma);
  auto row = s.step();
  if (!row) return row.error();
  return *row ? s.i64(0) : 0;
}

}  // namespace glimpse::server::sql
