#include "store_schema.h"

#include <iterator>
#include <string>

#include "sqlite.h"

namespace glimpse::server {
namespace {

using sql::Exec;
using sql::PragmaInt;
using sql::WriteTxn;

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
    // 4: the version a version was grown from ("name:version", '' none), and the training set kept
    // beside a version so it can grow (every row's features; none for versions stored before).
    R"sql(
    ALTER TABLE versions ADD COLUMN grown_from TEXT NOT NULL DEFAULT '';
    CREATE TABLE training_sets (
      version_id INTEGER PRIMARY KEY REFERENCES versions(id) ON DELETE CASCADE,
      blob       BLOB NOT NULL,
      size_bytes INTEGER NOT NULL,
      sha256     TEXT NOT NULL
    );
    CREATE TRIGGER training_sets_immutable BEFORE UPDATE ON training_sets
      BEGIN SELECT RAISE(ABORT, 'training sets are immutable'); END;
    )sql",
};
constexpr int kSchemaVersion = static_cast<int>(std::size(kMigrations));

}  // namespace

int LatestStoreSchema() { return kSchemaVersion; }

Status MigrateStore(sqlite3* db) {
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

}  // namespace glimpse::server
