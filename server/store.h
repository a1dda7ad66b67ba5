// ModelStore: immutable model versions in one SQLite file (or ":memory:" in tests).
// Each write is one BEGIN IMMEDIATE transaction, so a half-written model is never visible and a crash
// mid-write leaves earlier versions intact. Several processes may share the file (WAL + busy timeout);
// every lookup re-reads the database, so versions written elsewhere are seen without a restart.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/model.h"

struct sqlite3;

namespace glimpse::server {

inline constexpr const char* kDefaultDbPath = "./var/glimpse.db";

// Metadata of one stored version (everything but the blob).
struct ModelRecord {
  int64_t id = 0;  // unique in this file, never reused
  std::string name;
  uint32_t version = 0;  // 1, 2, ... per name, never reused
  bool is_default = false;
  int64_t created_unix_ms = 0;
  std::string description;
  std::vector<MethodId> methods;
  MethodId default_method = MethodId::kFusion;
  std::string params;  // the TrainParameters training used (JSON); older versions: the request's
  TrainingSummary stats;  // categories and clouds_per_category in the model's order, extents
  uint32_t feature_version = 0;  // the model's feature pipeline version; 0: stored before it was recorded
  uint64_t size_bytes = 0;
  std::string sha256;  // hex digest of the blob
  std::string grown_from;  // "name:version" of the version it was grown from; empty: none
  uint64_t training_set_bytes = 0;  // the training set kept beside it; 0: none (it cannot grow)
};

// What Put stores: a new version of `name`.
struct NewModel {
  std::string name;
  std::string description;
  std::vector<MethodId> methods;
  MethodId default_method = MethodId::kFusion;
  std::string params;
  TrainingSummary stats;
  std::vector<uint8_t> blob;
  uint32_t feature_version = 0;  // Model::feature_version
  std::string grown_from;             // ModelRecord::grown_from
  std::vector<uint8_t> training_set;  // kept beside the model (empty: none)
};

struct StoreOptions {
  int busy_timeout_ms = 5000;
  // Test hook: runs inside Put's transaction just before COMMIT; an error rolls the write back.
  std::function<Status()> before_commit;
};

class ModelStore {
 public:
  // Opens (creating the file and its folder when missing) and migrates the schema. A read-only,
  // corrupt or newer-schema file is an error that says so.
  static Expected<std::unique_ptr<ModelStore>> Open(const std::string& path, StoreOptions options = {});
  ~ModelStore();
  ModelStore(const ModelStore&) = delete;
  ModelStore& operator=(const ModelStore&) = delete;

  Expected<ModelRecord> Put(const NewModel& model);
  // version 0: the name's default version (the pinned one, else the latest).
  Expected<ModelRecord> Get(std::string_view name, uint32_t version) const;
  Expected<ModelRecord> GetById(int64_t id) const;
  // Every version, by name then version; name_filter non-empty: only that name's versions.
  Expected<std::vector<ModelRecord>> List(std::string_view name_filter = {}) const;
  // The serialized model, checked against its digest (DATA_LOSS when it does not match).
  Expected<std::vector<uint8_t>> Blob(int64_t id) const;
  // The training set kept beside a version, checked against its digest (DATA_LOSS when it does not
  // match); FAILED_PRECONDITION when none is kept.
  Expected<std::vector<uint8_t>> TrainingSet(int64_t id) const;
  // version 0: every version of the name. Returns the deleted versions.
  Expected<std::vector<uint32_t>> Delete(std::string_view name, uint32_t version);
  // version 0: unpin, serve the latest. Returns the record now served by default.
  Expected<ModelRecord> SetDefault(std::string_view name, uint32_t version);
  // Ids of every stored version (for dropping cache entries deleted by other processes).
  Expected<std::vector<int64_t>> Ids() const;

  // Changes whenever another connection (e.g. another server process) commits to the file.
  int64_t DataVersion() const;
  int SchemaVersion() const;
  static int LatestSchemaVersion();

 private:
  explicit ModelStore(sqlite3* db, StoreOptions options);
  Expected<std::vector<ModelRecord>> Query(std::string_view where, const std::vector<std::string>& args) const;

  sqlite3* db_;
  StoreOptions options_;
  mutable std::mutex mutex_;  // one connection, used by one thread at a time
};

// Hex SHA-256 of bytes.
std::string Sha256Hex(std::span<const uint8_t> bytes);

}  // namespace glimpse::server
