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

#include "sqlite.h"
#include "store_schema.h"

namespace glimpse::server {
namespace {

using sql::Exec;
using sql::PragmaInt;
using sql::SqlError;
using sql::Stmt;
using sql::WriteTxn;

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

constexpr const char* kSelectRecord = R"sql(
  SELECT v.id, v.name, v.version,
         EXISTS(SELECT 1 FROM served s WHERE s.name = v.name AND s.version = v.version),
         v.created_unix_ms, v.description, v.methods, v.default_method, v.params, v.size_bytes, v.sha256,
         t.clouds, t.objects, t.keypoints, t.seconds, v.feature_version, t.min_extent_m, t.max_extent_m,
         v.grown_from, COALESCE(ts.size_bytes, 0)
    FROM versions v LEFT JOIN training_stats t ON t.version_id = v.id
                    LEFT JOIN training_sets ts ON ts.version_id = v.id )sql";

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
  if (!in_memory) {
    // A file whose pages are damaged past its header opens and migrates; the store would then say
    // SERVING and fail every call. quick_check reads every page once (model-sync.sh checks the same).
    Stmt check(db, "PRAGMA quick_check");
    auto row = check.step();
    if (!row) return fail(row.error());
    if (!*row || check.text(0) != "ok")
      return data_loss(path + ": model store corrupt (quick_check: " + (*row ? check.text(0) : "no answer") + ")");
  }
  if (Status s = MigrateStore(db); !s.ok()) return fail(s.error());
  return store;
}

ModelStore::ModelStore(sqlite3* db, StoreOptions options) : db_(db), options_(std::move(options)) {}

ModelStore::~ModelStore() { sqlite3_close_v2(db_); }

int ModelStore::LatestSchemaVersion() { return LatestStoreSchema(); }

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
    r.grown_from = s.text(18);
    r.training_set_bytes = static_cast<uint64_t>(s.i64(19));
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
             " params, blob, size_bytes, sha256, feature_version, grown_from)"
             " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    ins.bind(1, model.name).bind(2, version).bind(3, NowUnixMs()).bind(4, model.description);
    ins.bind(5, JoinMethods(model.methods)).bind(6, MethodToken(model.default_method)).bind(7, model.params);
    ins.bind_blob(8, model.blob).bind(9, static_cast<int64_t>(model.blob.size())).bind(10, Sha256Hex(model.blob));
    ins.bind(11, static_cast<int64_t>(model.feature_version)).bind(12, model.grown_from);
    if (Status s = ins.run(); !s.ok()) return s.error();
    id = sqlite3_last_insert_rowid(db_);
    if (!model.training_set.empty()) {
      Stmt set(db_, "INSERT INTO training_sets (version_id, blob, size_bytes, sha256) VALUES (?, ?, ?, ?)");
      set.bind(1, id).bind_blob(2, model.training_set).bind(3, static_cast<int64_t>(model.training_set.size()));
      set.bind(4, Sha256Hex(model.training_set));
      if (Status s = set.run(); !s.ok()) return s.error();
    }

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

Expected<std::vector<uint8_t>> ModelStore::TrainingSet(int64_t id) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, "SELECT blob, sha256 FROM training_sets WHERE version_id = ?");
  s.bind(1, id);
  auto row = s.step();
  if (!row) return row.error();
  if (!*row) return failed_precondition("model id " + std::to_string(id) + " keeps no training set");
  std::vector<uint8_t> blob = s.blob(0);
  if (Sha256Hex(blob) != s.text(1))
    return data_loss("the training set of model id " + std::to_string(id) + " does not match its sha256");
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
