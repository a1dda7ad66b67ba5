#include "store.h"

#include <openssl/sha.h>
#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace glimpse::server {
namespace {

// Schema migrations: entry i takes `PRAGMA user_version` from i to i + 1. Append, never edit.
constexpr const char* kMigrations[] = {
    // 1: models (a name and its pinned default), immutable versions, categories, training stats.
    R"sql(
    CREATE TABLE models (
      name            TEXT PRIMARY KEY,
      default_version INTEGER,                  -- NULL: serve the latest version
      next_version    INTEGER NOT NULL DEFAULT 1 -- versions are never reused, even after a delete
    );
    CREATE TABLE versions (
      id              INTEGER PRIMARY KEY AUTOINCREMENT,
      name            TEXT NOT NULL REFERENCES models(name) ON DELETE CASCADE,
      version         INTEGER NOT NULL,
      created_unix_ms INTEGER NOT NULL,
      description     TEXT NOT NULL DEFAULT '',
      methods         TEXT NOT NULL,            -- comma-separated method names
      default_method  TEXT NOT NULL,
      params          TEXT NOT NULL DEFAULT '', -- TrainParameters as JSON
      blob            BLOB NOT NULL,
      size_bytes      INTEGER NOT NULL,
      sha256          TEXT NOT NULL,
      UNIQUE (name, version)
    );
    CREATE TABLE categories (
      version_id INTEGER NOT NULL REFERENCES versions(id) ON DELETE CASCADE,
      position   INTEGER NOT NULL,
      name       TEXT NOT NULL,
      clouds     INTEGER NOT NULL DEFAULT 0,
      PRIMARY KEY (version_id, position)
    );
    CREATE TABLE training_stats (
      version_id INTEGER PRIMARY KEY REFERENCES versions(id) ON DELETE CASCADE,
      clouds     INTEGER NOT NULL,
      objects    INTEGER NOT NULL,
      keypoints  INTEGER NOT NULL,
      seconds    REAL NOT NULL
    );
    -- The version each name serves by default: the pinned one while it exists, else the latest.
    CREATE VIEW served AS
      SELECT m.name AS name,
             COALESCE((SELECT v.version FROM versions v
                        WHERE v.name = m.name AND v.version = m.default_version),
                      (SELECT MAX(v.version) FROM versions v WHERE v.name = m.name)) AS version
        FROM models m;
    )sql",
    // 2: versions are immutable: the database refuses updates, not just the code.
    R"sql(
    CREATE TRIGGER versions_immutable BEFORE UPDATE ON versions
      BEGIN SELECT RAISE(ABORT, 'model versions are immutable'); END;
    )sql",
    // 3: the feature pipeline version a model was trained with (0: stored before it was recorded), and
    // the extents of the clouds it learnt (0: unknown).
    R"sql(
    ALTER TABLE versions ADD COLUMN feature_version INTEGER NOT NULL DEFAULT 0;
    ALTER TABLE training_stats ADD COLUMN min_extent_m REAL NOT NULL DEFAULT 0;
    ALTER TABLE training_stats ADD COLUMN max_extent_m REAL NOT NULL DEFAULT 0;
    )sql",
};
constexpr int kSchemaVersion = static_cast<int>(std::size(kMigrations));

std::string MethodToken(MethodId m) { return method_name(m); }

Expected<MethodId> ParseMethodToken(std::string_view token) {
  auto m = parse_method(token);
  if (!m.ok()) return data_loss("stored model names an unknown method '" + std::string(token) + "'");
  return *m;
}

std::string JoinMethods(const std::vector<MethodId>& methods) {
  std::string out;
  for (MethodId m : methods) {
    if (!out.empty()) out += ',';
    out += MethodToken(m);
  }
  return out;
}

Expected<std::vector<MethodId>> SplitMethods(const std::string& text) {
  std::vector<MethodId> out;
  std::stringstream in(text);
  for (std::string token; std::getline(in, token, ',');) {
    if (token.empty()) continue;
    auto m = ParseMethodToken(token);
    if (!m) return m.error();
    out.push_back(*m);
  }
  return out;
}

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

Status Exec(sqlite3* db, const char* sql) {
  char* msg = nullptr;
  int rc = sqlite3_exec(db, sql, nullptr, nullptr, &msg);
  if (rc == SQLITE_OK) return {};
  std::string what = msg ? msg : sqlite3_errstr(rc);
  sqlite3_free(msg);
  return SqlError(nullptr, rc, what);
}

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

Expected<int64_t> PragmaInt(sqlite3* db, const char* pragma) {
  Stmt s(db, pragma);
  auto row = s.step();
  if (!row) return row.error();
  return *row ? s.i64(0) : 0;
}

Status Migrate(sqlite3* db) {
  WriteTxn txn(db);
  if (!txn.begun().ok()) return txn.begun();
  auto current = PragmaInt(db, "PRAGMA user_version");
  if (!current) return current.error();
  if (*current > kSchemaVersion)
    return failed_precondition("model store schema version " + std::to_string(*current) +
                               " is newer than this server's (" + std::to_string(kSchemaVersion) +
                               "); upgrade the server");
  for (int v = static_cast<int>(*current); v < kSchemaVersion; ++v) {
    if (Status s = Exec(db, kMigrations[v]); !s.ok())
      return Error{s.error().code, "migration to schema " + std::to_string(v + 1) + ": " + s.error().message};
  }
  if (*current != kSchemaVersion) {
    std::string set = "PRAGMA user_version = " + std::to_string(kSchemaVersion);
    if (Status s = Exec(db, set.c_str()); !s.ok()) return s;
  }
  return txn.commit();
}

constexpr const char* kSelectRecord = R"sql(
  SELECT v.id, v.name, v.version,
         EXISTS(SELECT 1 FROM served s WHERE s.name = v.name AND s.version = v.version),
         v.created_unix_ms, v.description, v.methods, v.default_method, v.params, v.size_bytes, v.sha256,
         t.clouds, t.objects, t.keypoints, t.seconds, v.feature_version, t.min_extent_m, t.max_extent_m
    FROM versions v LEFT JOIN training_stats t ON t.version_id = v.id )sql";

float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.f; }

int64_t NowUnixMs() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count();
}

}  // namespace

std::string Sha256Hex(std::span<const uint8_t> bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(bytes.data(), bytes.size(), digest);
  std::string hex;
  hex.reserve(2 * SHA256_DIGEST_LENGTH);
  char buf[3];
  for (unsigned char c : digest) {
    std::snprintf(buf, sizeof buf, "%02x", c);
    hex += buf;
  }
  return hex;
}

Expected<std::unique_ptr<ModelStore>> ModelStore::Open(const std::string& path, StoreOptions options) {
  const bool in_memory = path == ":memory:" || path.empty();
  if (!in_memory && path.rfind("file:", 0) != 0) {
    std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    if (ec) return failed_precondition("cannot create folder " + parent.string() + " for " + path + ": " + ec.message());
  }
  sqlite3* db = nullptr;
  int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX | SQLITE_OPEN_URI;
  int rc = sqlite3_open_v2(in_memory ? ":memory:" : path.c_str(), &db, flags, nullptr);
  std::unique_ptr<ModelStore> store(new ModelStore(db, std::move(options)));  // closes db on any return
  if (rc != SQLITE_OK) {
    Error e = SqlError(db, rc, "cannot open " + path);
    return e;
  }
  auto fail = [&](const Error& e) -> Error { return {e.code, path + ": " + e.message}; };
  if (sqlite3_db_readonly(db, "main") == 1)
    return failed_precondition(path + ": database file is read-only; the server needs to write to it");
  sqlite3_busy_timeout(db, store->options_.busy_timeout_ms);
  sqlite3_extended_result_codes(db, 1);
  if (Status s = Exec(db, "PRAGMA foreign_keys = ON"); !s.ok()) return fail(s.error());
  if (!in_memory) {
    Stmt wal(db, "PRAGMA journal_mode = WAL");
    auto row = wal.step();  // the first statement that reads the file: garbage fails here
    if (!row) return fail(row.error());
    if (!*row || wal.text(0) != "wal")
      return failed_precondition(path + ": cannot switch to WAL journal mode (got '" + (*row ? wal.text(0) : "") + "')");
  }
  if (Status s = Migrate(db); !s.ok()) return fail(s.error());
  return store;
}

ModelStore::ModelStore(sqlite3* db, StoreOptions options) : db_(db), options_(std::move(options)) {}

ModelStore::~ModelStore() { sqlite3_close_v2(db_); }

int ModelStore::LatestSchemaVersion() { return kSchemaVersion; }

int ModelStore::SchemaVersion() const {
  std::lock_guard lock(mutex_);
  auto v = PragmaInt(db_, "PRAGMA user_version");
  return v ? static_cast<int>(*v) : -1;
}

int64_t ModelStore::DataVersion() const {
  std::lock_guard lock(mutex_);
  auto v = PragmaInt(db_, "PRAGMA data_version");
  return v ? *v : -1;
}

Expected<std::vector<ModelRecord>> ModelStore::Query(std::string_view where,
                                                     const std::vector<std::string>& args) const {
  std::string sql = std::string(kSelectRecord) + std::string(where);
  Stmt s(db_, sql);
  for (size_t i = 0; i < args.size(); ++i) s.bind(static_cast<int>(i + 1), args[i]);
  std::vector<ModelRecord> out;
  for (;;) {
    auto row = s.step();
    if (!row) return row.error();
    if (!*row) break;
    ModelRecord r;
    r.id = s.i64(0);
    r.name = s.text(1);
    r.version = static_cast<uint32_t>(s.i64(2));
    r.is_default = s.i64(3) != 0;
    r.created_unix_ms = s.i64(4);
    r.description = s.text(5);
    auto methods = SplitMethods(s.text(6));
    if (!methods) return methods.error();
    r.methods = std::move(*methods);
    auto dm = ParseMethodToken(s.text(7));
    if (!dm) return dm.error();
    r.default_method = *dm;
    r.params = s.text(8);
    r.size_bytes = static_cast<uint64_t>(s.i64(9));
    r.sha256 = s.text(10);
    r.stats.clouds = static_cast<size_t>(s.i64(11));
    r.stats.objects = static_cast<size_t>(s.i64(12));
    r.stats.keypoints = static_cast<size_t>(s.i64(13));
    r.stats.seconds = s.f64(14);
    r.feature_version = static_cast<uint32_t>(s.i64(15));
    r.stats.min_extent_m = static_cast<float>(s.f64(16));
    r.stats.max_extent_m = static_cast<float>(s.f64(17));
    out.push_back(std::move(r));
  }
  for (ModelRecord& r : out) {
    Stmt c(db_, "SELECT name, clouds FROM categories WHERE version_id = ? ORDER BY position");
    c.bind(1, r.id);
    for (;;) {
      auto row = c.step();
      if (!row) return row.error();
      if (!*row) break;
      r.stats.categories.push_back(c.text(0));
      r.stats.clouds_per_category.push_back(static_cast<size_t>(c.i64(1)));
    }
  }
  return out;
}

Expected<ModelRecord> ModelStore::Put(const NewModel& model) {
  if (model.name.empty()) return invalid_argument("model name is empty");
  if (!model.stats.clouds_per_category.empty() &&
      model.stats.clouds_per_category.size() != model.stats.categories.size())
    return invalid_argument("clouds_per_category does not match categories");
  std::lock_guard lock(mutex_);
  int64_t id = 0;
  {
    WriteTxn txn(db_);
    if (!txn.begun().ok()) return txn.begun().error();
    if (Status s = Stmt(db_, "INSERT INTO models (name) VALUES (?) ON CONFLICT (name) DO NOTHING")
                       .bind(1, model.name).run();
        !s.ok())
      return s.error();
    Stmt next(db_, "UPDATE models SET next_version = next_version + 1 WHERE name = ? RETURNING next_version - 1");
    next.bind(1, model.name);
    auto row = next.step();
    if (!row) return row.error();
    if (!*row) return internal_error("model store: no models row for " + model.name);
    const int64_t version = next.i64(0);
    if (Status s = next.run(); !s.ok()) return s.error();  // finish the UPDATE

    Stmt ins(db_,
             "INSERT INTO versions (name, version, created_unix_ms, description, methods, default_method,"
             " params, blob, size_bytes, sha256, feature_version) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    ins.bind(1, model.name).bind(2, version).bind(3, NowUnixMs()).bind(4, model.description);
    ins.bind(5, JoinMethods(model.methods)).bind(6, MethodToken(model.default_method)).bind(7, model.params);
    ins.bind_blob(8, model.blob).bind(9, static_cast<int64_t>(model.blob.size())).bind(10, Sha256Hex(model.blob));
    ins.bind(11, static_cast<int64_t>(model.feature_version));
    if (Status s = ins.run(); !s.ok()) return s.error();
    id = sqlite3_last_insert_rowid(db_);

    for (size_t i = 0; i < model.stats.categories.size(); ++i) {
      int64_t clouds = i < model.stats.clouds_per_category.size()
                           ? static_cast<int64_t>(model.stats.clouds_per_category[i]) : 0;
      Stmt cat(db_, "INSERT INTO categories (version_id, position, name, clouds) VALUES (?, ?, ?, ?)");
      cat.bind(1, id).bind(2, static_cast<int64_t>(i)).bind(3, model.stats.categories[i]).bind(4, clouds);
      if (Status s = cat.run(); !s.ok()) return s.error();
    }
    Stmt st(db_,
            "INSERT INTO training_stats (version_id, clouds, objects, keypoints, seconds, min_extent_m, max_extent_m)"
            " VALUES (?, ?, ?, ?, ?, ?, ?)");
    st.bind(1, id).bind(2, static_cast<int64_t>(model.stats.clouds));
    st.bind(3, static_cast<int64_t>(model.stats.objects)).bind(4, static_cast<int64_t>(model.stats.keypoints));
    st.bind(5, model.stats.seconds);
    st.bind(6, static_cast<double>(finite_or_zero(model.stats.min_extent_m)));
    st.bind(7, static_cast<double>(finite_or_zero(model.stats.max_extent_m)));
    if (Status s = st.run(); !s.ok()) return s.error();

    if (options_.before_commit) {
      if (Status s = options_.before_commit(); !s.ok()) return s.error();
    }
    if (Status s = txn.commit(); !s.ok()) return s.error();
  }
  auto rows = Query("WHERE v.id = ?", {std::to_string(id)});
  if (!rows) return rows.error();
  if (rows->empty()) return internal_error("model store: version " + std::to_string(id) + " vanished after commit");
  return std::move(rows->front());
}

Expected<ModelRecord> ModelStore::Get(std::string_view name, uint32_t version) const {
  std::lock_guard lock(mutex_);
  std::string n(name);
  auto rows = version == 0
                  ? Query("WHERE v.name = ?1 AND v.version = (SELECT version FROM served WHERE name = ?1)", {n})
                  : Query("WHERE v.name = ?1 AND v.version = ?2", {n, std::to_string(version)});
  if (!rows) return rows.error();
  if (rows->empty())
    return not_found(version == 0 ? "model '" + n + "' not found"
                                  : "model '" + n + "' version " + std::to_string(version) + " not found");
  return std::move(rows->front());
}

Expected<ModelRecord> ModelStore::GetById(int64_t id) const {
  std::lock_guard lock(mutex_);
  auto rows = Query("WHERE v.id = ?", {std::to_string(id)});
  if (!rows) return rows.error();
  if (rows->empty()) return not_found("model id " + std::to_string(id) + " not found");
  return std::move(rows->front());
}

Expected<std::vector<ModelRecord>> ModelStore::List(std::string_view name_filter) const {
  std::lock_guard lock(mutex_);
  if (name_filter.empty()) return Query("ORDER BY v.name, v.version", {});
  return Query("WHERE v.name = ? ORDER BY v.version", {std::string(name_filter)});
}

Expected<std::vector<uint8_t>> ModelStore::Blob(int64_t id) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT blob, sha256 FROM versions WHERE id = ?");
  s.bind(1, id);
  auto row = s.step();
  if (!row) return row.error();
  if (!*row) return not_found("model id " + std::to_string(id) + " not found");
  std::vector<uint8_t> blob = s.blob(0);
  if (Sha256Hex(blob) != s.text(1))
    return data_loss("stored model id " + std::to_string(id) + " does not match its sha256");
  return blob;
}

Expected<std::vector<uint32_t>> ModelStore::Delete(std::string_view name, uint32_t version) {
  std::lock_guard lock(mutex_);
  WriteTxn txn(db_);
  if (!txn.begun().ok()) return txn.begun().error();
  std::string n(name);
  Stmt del(db_, version == 0 ? "DELETE FROM versions WHERE name = ?1 RETURNING version"
                             : "DELETE FROM versions WHERE name = ?1 AND version = ?2 RETURNING version");
  del.bind(1, n);
  if (version != 0) del.bind(2, static_cast<int64_t>(version));
  std::vector<uint32_t> deleted;
  for (;;) {
    auto row = del.step();
    if (!row) return row.error();
    if (!*row) break;
    deleted.push_back(static_cast<uint32_t>(del.i64(0)));
  }
  if (deleted.empty())
    return not_found(version == 0 ? "model '" + n + "' not found"
                                  : "model '" + n + "' version " + std::to_string(version) + " not found");
  // The name row stays (it remembers next_version, so versions are never reused); a pin on a deleted
  // version is dropped so the name falls back to its latest.
  if (Status s = Stmt(db_, "UPDATE models SET default_version = NULL WHERE name = ?1 AND default_version "
                           "NOT IN (SELECT version FROM versions WHERE name = ?1)")
                     .bind(1, n).run();
      !s.ok())
    return s.error();
  if (Status s = txn.commit(); !s.ok()) return s.error();
  std::sort(deleted.begin(), deleted.end());
  return deleted;
}

Expected<ModelRecord> ModelStore::SetDefault(std::string_view name, uint32_t version) {
  std::string n(name);
  {
    std::lock_guard lock(mutex_);
    WriteTxn txn(db_);
    if (!txn.begun().ok()) return txn.begun().error();
    Stmt exists(db_, version == 0 ? "SELECT 1 FROM versions WHERE name = ?1 LIMIT 1"
                                  : "SELECT 1 FROM versions WHERE name = ?1 AND version = ?2");
    exists.bind(1, n);
    if (version != 0) exists.bind(2, static_cast<int64_t>(version));
    auto row = exists.step();
    if (!row) return row.error();
    if (!*row)
      return not_found(version == 0 ? "model '" + n + "' not found"
                                    : "model '" + n + "' version " + std::to_string(version) + " not found");
    Stmt pin(db_, "UPDATE models SET default_version = ?2 WHERE name = ?1");
    pin.bind(1, n);
    if (version == 0) pin.bind_null(2); else pin.bind(2, static_cast<int64_t>(version));
    if (Status s = pin.run(); !s.ok()) return s.error();
    if (Status s = txn.commit(); !s.ok()) return s.error();
  }
  return Get(n, 0);
}

Expected<std::vector<int64_t>> ModelStore::Ids() const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT id FROM versions");
  std::vector<int64_t> ids;
  for (;;) {
    auto row = s.step();
    if (!row) return row.error();
    if (!*row) break;
    ids.push_back(s.i64(0));
  }
  return ids;
}

}  // namespace glimpse::server
