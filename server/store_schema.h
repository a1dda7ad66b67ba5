// The model store's SQLite schema (store.cc): migrations applied in order under `PRAGMA user_version`.
#pragma once

#include <sqlite3.h>

#include "glimpse/expected.h"

namespace glimpse::server {

// The schema version this server writes (the number of migrations).
int LatestStoreSchema();

// Brings the database to LatestStoreSchema() in one write transaction; a newer schema is a
// failed_precondition naming both versions, a failed migration names its number.
Status MigrateStore(sqlite3* db);

}  // namespace glimpse::server
