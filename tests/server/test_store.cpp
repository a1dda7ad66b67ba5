// ModelStore: schema and migrations, WAL, immutable versions, delete, default pins, two stores on one
// file, a crash mid-write, bad files; and ModelCache over it.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/temp_dir.h"
#include "fakes.h"
#include "server/model_cache.h"
#include "server/store.h"

namespace glimpse::server {
namespace {

namespace fs = std::filesystem;
using glimpse::testing::TempDir;

NewModel Sample(const std::string& name, const std::string& tag = "a") {
  NewModel m;
  m.name = name;
  m.description = "model " + tag;
  m.methods = {MethodId::kBoK, MethodId::kFusion};
  m.default_method = MethodId::kFusion;
  m.params = R"({"seed":"7"})";
  m.stats.clouds = 4;
  m.stats.objects = 2;
  m.stats.keypoints = 40;
  m.stats.categories = {"box", "sphere"};
  m.stats.clouds_per_category = {3, 1};
  m.stats.seconds = 1.5;
  Model model;
  model.categories = {"box", "sphere"};
  model.methods = m.methods;
  m.blob = testing::FakeSerialize(model);
  m.blob.push_back(static_cast<uint8_t>(tag[0]));  // distinct bytes per tag (not deserializable: fine here)
  return m;
}

std::unique_ptr<ModelStore> OpenOk(const std::string& path, StoreOptions options = {}) {
  auto s = ModelStore::Open(path, std::move(options));
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  return s.ok() ? std::move(*s) : nullptr;
}

// Runs SQL on the file through a separate raw connection (another "process").
void RawExec(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* err = nullptr;
  int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << msg;
}

TEST(Store, EmptyStoreHasNothing) {
  auto store = OpenOk(":memory:");
  auto all = store->List();
  ASSERT_TRUE(all.ok());
  EXPECT_TRUE(all->empty());
  EXPECT_EQ(store->Get("x", 0).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Get("x", 3).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Delete("x", 0).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->SetDefault("x", 0).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Blob(1).error().code, ErrorCode::kNotFound);
}

TEST(Store, FreshDatabaseIsAtTheLatestSchemaInWalMode) {
  TempDir dir;
  const std::string path = dir.file("nested/folder/glimpse.db");  // the folders are created
  auto store = OpenOk(path);
  ASSERT_TRUE(store);
  EXPECT_EQ(store->SchemaVersion(), ModelStore::LatestSchemaVersion());
  EXPECT_GE(ModelStore::LatestSchemaVersion(), 2);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "PRAGMA journal_mode", -1, &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "wal");
  sqlite3_finalize(st);
  sqlite3_close(db);
}

TEST(Store, PutGetAndVersionsCountUpPerName) {
  auto store = OpenOk(":memory:");
  auto a1 = store->Put(Sample("chairs", "a"));
  ASSERT_TRUE(a1.ok()) << a1.error().message;
  auto a2 = store->Put(Sample("chairs", "b"));
  auto b1 = store->Put(Sample("tables", "c"));
  ASSERT_TRUE(a2.ok() && b1.ok());
  EXPECT_EQ(a1->version, 1u);
  EXPECT_EQ(a2->version, 2u);
  EXPECT_EQ(b1->version, 1u);
  EXPECT_NE(a1->id, a2->id);

  auto got = store->Get("chairs", 1);
  ASSERT_TRUE(got.ok());
  EXPECT_EQ(got->description, "model a");
  EXPECT_EQ(got->methods, (std::vector<MethodId>{MethodId::kBoK, MethodId::kFusion}));
  EXPECT_EQ(got->default_method, MethodId::kFusion);
  EXPECT_EQ(got->params, R"({"seed":"7"})");
  EXPECT_EQ(got->stats.categories, (std::vector<std::string>{"box", "sphere"}));
  EXPECT_EQ(got->stats.clouds_per_category, (std::vector<size_t>{3, 1}));
  EXPECT_EQ(got->stats.clouds, 4u);
  EXPECT_EQ(got->stats.objects, 2u);
  EXPECT_EQ(got->stats.keypoints, 40u);
  EXPECT_DOUBLE_EQ(got->stats.seconds, 1.5);
  EXPECT_EQ(got->size_bytes, Sample("chairs", "a").blob.size());
  EXPECT_EQ(got->sha256, Sha256Hex(Sample("chairs", "a").blob));
  EXPECT_GT(got->created_unix_ms, 1'600'000'000'000);
  EXPECT_FALSE(got->is_default);

  auto latest = store->Get("chairs", 0);
  ASSERT_TRUE(latest.ok());
  EXPECT_EQ(latest->version, 2u);
  EXPECT_TRUE(latest->is_default);

  auto blob = store->Blob(a1->id);
  ASSERT_TRUE(blob.ok());
  EXPECT_EQ(*blob, Sample("chairs", "a").blob);

  auto all = store->List();
  ASSERT_TRUE(all.ok());
  ASSERT_EQ(all->size(), 3u);
  EXPECT_EQ((*all)[0].name, "chairs");
  EXPECT_EQ((*all)[1].version, 2u);
  EXPECT_EQ((*all)[2].name, "tables");
  auto only = store->List("tables");
  ASSERT_TRUE(only.ok());
  EXPECT_EQ(only->size(), 1u);
}

TEST(Store, Sha256OfKnownInput) {
  const std::string abc = "abc";
  EXPECT_EQ(Sha256Hex({reinterpret_cast<const uint8_t*>(abc.data()), abc.size()}),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Store, VersionsAreImmutableInTheDatabaseItself) {
  TempDir dir;
  const std::string path = dir.file("g.db");
  {
    auto store = OpenOk(path);
    ASSERT_TRUE(store->Put(Sample("m")).ok());
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* err = nullptr;
  int rc = sqlite3_exec(db, "UPDATE versions SET description = 'changed'", nullptr, nullptr, &err);
  EXPECT_NE(rc, SQLITE_OK);
  EXPECT_NE(std::string(err ? err : "").find("immutable"), std::string::npos);
  sqlite3_free(err);
  sqlite3_close(db);
  auto store = OpenOk(path);
  EXPECT_EQ(store->Get("m", 1)->description, "model a");
}

TEST(Store, DeleteOneVersionOrAllAndNeverReuseVersionNumbers) {
  auto store = OpenOk(":memory:");
  for (const char* tag : {"a", "b", "c"}) ASSERT_TRUE(store->Put(Sample("m", tag)).ok());
  auto deleted = store->Delete("m", 3);
  ASSERT_TRUE(deleted.ok());
  EXPECT_EQ(*deleted, std::vector<uint32_t>{3});
  EXPECT_EQ(store->Get("m", 3).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Get("m", 0)->version, 2u);  // the latest remaining
  EXPECT_EQ(store->Delete("m", 3).error().code, ErrorCode::kNotFound);

  auto next = store->Put(Sample("m", "d"));
  ASSERT_TRUE(next.ok());
  EXPECT_EQ(next->version, 4u);  // 3 is gone for good, never a different model

  auto all = store->Delete("m", 0);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(*all, (std::vector<uint32_t>{1, 2, 4}));
  EXPECT_TRUE(store->List()->empty());
  EXPECT_EQ(store->Get("m", 0).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Put(Sample("m", "e"))->version, 5u);
}

TEST(Store, KeepsATrainingSetBesideAVersionUntilItIsDeleted) {
  TempDir dir;
  const std::string path = dir.file("g.db");
  auto store = OpenOk(path);
  NewModel with = Sample("m", "a");
  with.training_set = {1, 2, 3, 4, 5};
  with.grown_from = "base:2";
  auto kept = store->Put(with);
  auto without = store->Put(Sample("m", "b"));
  ASSERT_TRUE(kept.ok() && without.ok());
  EXPECT_EQ(kept->training_set_bytes, 5u);
  EXPECT_EQ(kept->grown_from, "base:2");
  EXPECT_EQ(without->training_set_bytes, 0u);
  EXPECT_EQ(without->grown_from, "");
  EXPECT_EQ(*store->TrainingSet(kept->id), with.training_set);
  EXPECT_EQ(store->TrainingSet(without->id).error().code, ErrorCode::kFailedPrecondition);
  EXPECT_EQ(store->Get("m", 1)->training_set_bytes, 5u);

  RawExec(path, "DROP TRIGGER training_sets_immutable; UPDATE training_sets SET blob = x'00';");
  EXPECT_EQ(store->TrainingSet(kept->id).error().code, ErrorCode::kDataLoss);
  ASSERT_TRUE(store->Delete("m", 1).ok());
  EXPECT_EQ(store->TrainingSet(kept->id).error().code, ErrorCode::kFailedPrecondition);  // deleted with it
}

TEST(Store, SetDefaultPinsAVersionAndFallsBackToLatest) {
  auto store = OpenOk(":memory:");
  for (const char* tag : {"a", "b", "c"}) ASSERT_TRUE(store->Put(Sample("m", tag)).ok());
  auto pinned = store->SetDefault("m", 2);
  ASSERT_TRUE(pinned.ok());
  EXPECT_EQ(pinned->version, 2u);
  EXPECT_TRUE(pinned->is_default);
  EXPECT_EQ(store->Get("m", 0)->version, 2u);
  EXPECT_FALSE(store->Get("m", 3)->is_default);

  ASSERT_TRUE(store->Put(Sample("m", "d")).ok());  // a new version does not move the pin
  EXPECT_EQ(store->Get("m", 0)->version, 2u);

  EXPECT_EQ(store->SetDefault("m", 9).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(store->Get("m", 0)->version, 2u);

  ASSERT_TRUE(store->Delete("m", 2).ok());  // deleting the pinned version: back to the latest
  EXPECT_EQ(store->Get("m", 0)->version, 4u);

  ASSERT_TRUE(store->SetDefault("m", 1).ok());
  auto unpinned = store->SetDefault("m", 0);
  ASSERT_TRUE(unpinned.ok());
  EXPECT_EQ(unpinned->version, 4u);
}

TEST(Store, TwoStoresOnOneFileSeeEachOthersWrites) {
  TempDir dir;
  const std::string path = dir.file("shared.db");
  auto a = OpenOk(path);
  auto b = OpenOk(path);
  ASSERT_TRUE(a && b);
  const int64_t before = b->DataVersion();
  auto put = a->Put(Sample("m", "a"));
  ASSERT_TRUE(put.ok());
  EXPECT_NE(b->DataVersion(), before);  // b notices a's commit
  auto seen = b->Get("m", 0);
  ASSERT_TRUE(seen.ok());
  EXPECT_EQ(seen->id, put->id);
  ASSERT_TRUE(b->Put(Sample("m", "b")).ok());
  EXPECT_EQ(a->Get("m", 0)->version, 2u);
  ASSERT_TRUE(b->SetDefault("m", 1).ok());
  EXPECT_EQ(a->Get("m", 0)->version, 1u);
  ASSERT_TRUE(a->Delete("m", 1).ok());
  EXPECT_EQ(b->Get("m", 1).error().code, ErrorCode::kNotFound);
}

TEST(Store, FailedWriteIsRolledBackAndInvisible) {
  bool fail = false;
  StoreOptions options;
  options.before_commit = [&fail]() -> Status {
    if (fail) return internal_error("injected failure before COMMIT");
    return {};
  };
  auto store = OpenOk(":memory:", options);
  ASSERT_TRUE(store->Put(Sample("m", "a")).ok());
  fail = true;
  auto r = store->Put(Sample("m", "b"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInternal);
  fail = false;
  EXPECT_EQ(store->List()->size(), 1u);
  EXPECT_EQ(store->Get("m", 0)->version, 1u);
  EXPECT_EQ(store->Put(Sample("m", "c"))->version, 2u);  // the rolled-back version number is free again
}

// The process dies between the version's INSERTs and COMMIT: earlier versions are intact and the
// half-written one never shows up.
TEST(StoreDeathTest, CrashMidWriteLeavesEarlierVersionsIntact) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  TempDir dir;
  const std::string path = dir.file("crash.db");
  {
    auto store = OpenOk(path);
    ASSERT_TRUE(store->Put(Sample("m", "a")).ok());
  }
  EXPECT_EXIT(
      {
        StoreOptions options;
        options.before_commit = []() -> Status { ::_exit(3); };
        auto store = ModelStore::Open(path, options);
        if (!store.ok()) ::_exit(1);
        (void)(*store)->Put(Sample("m", "b"));
        ::_exit(0);
      },
      ::testing::ExitedWithCode(3), "");
  auto store = OpenOk(path);
  auto all = store->List();
  ASSERT_TRUE(all.ok());
  ASSERT_EQ(all->size(), 1u);
  EXPECT_EQ((*all)[0].version, 1u);
  EXPECT_TRUE(store->Blob((*all)[0].id).ok());
  EXPECT_EQ(store->Put(Sample("m", "c"))->version, 2u);
}

TEST(Store, CorruptBlobIsDataLoss) {
  TempDir dir;
  const std::string path = dir.file("g.db");
  int64_t id = 0;
  {
    auto store = OpenOk(path);
    id = store->Put(Sample("m"))->id;
  }
  // Bypass the immutability trigger, as disk corruption would.
  RawExec(path, "DROP TRIGGER versions_immutable; UPDATE versions SET blob = x'00';");
  auto store = OpenOk(path);  // re-creates nothing: the schema version is already current
  EXPECT_EQ(store->Blob(id).error().code, ErrorCode::kDataLoss);
}

// Pages damaged past the header: the file still opens and migrates, and without a check at startup the
// server would say SERVING and fail every call. Open reads every page once and refuses it.
TEST(Store, APageDamagedPastTheHeaderIsAClearOpenError) {
  TempDir dir;
  const std::string path = dir.file("g.db");
  {
    auto store = OpenOk(path);
    NewModel big = Sample("m");
    big.blob.assign(64 * 1024, 7);  // pages enough to damage some
    ASSERT_TRUE(store->Put(big).ok());
  }
  ASSERT_GT(std::filesystem::file_size(path), 8u * 4096u);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4096);
    const std::string garbage(3 * 4096, '\x5a');
    f.write(garbage.data(), std::streamsize(garbage.size()));
  }
  auto store = ModelStore::Open(path);
  ASSERT_FALSE(store.ok());
  EXPECT_EQ(store.error().code, ErrorCode::kDataLoss) << store.error().message;
  EXPECT_NE(store.error().message.find("g.db"), std::string::npos) << store.error().message;
}

TEST(Store, MigratesAnOlderSchema) {
  TempDir dir;
  const std::string path = dir.file("old.db");
  {
    auto store = OpenOk(path);
    ASSERT_TRUE(store->Put(Sample("m")).ok());
  }
  // As a schema-1 server left it: no trigger (2), no feature version or extents (3), no grown_from or
  // training sets (4).
  RawExec(path,
          "DROP TABLE training_sets; ALTER TABLE versions DROP COLUMN grown_from;"
          " DROP TRIGGER versions_immutable; ALTER TABLE versions DROP COLUMN feature_version;"
          " ALTER TABLE training_stats DROP COLUMN min_extent_m; ALTER TABLE training_stats DROP COLUMN max_extent_m;"
          " PRAGMA user_version = 1;");
  auto store = OpenOk(path);
  ASSERT_TRUE(store);
  EXPECT_EQ(store->SchemaVersion(), ModelStore::LatestSchemaVersion());
  EXPECT_EQ(store->Get("m", 1)->description, "model a");  // data kept
  EXPECT_EQ(store->Get("m", 1)->feature_version, 0u);     // unknown for a version stored before it was recorded
  EXPECT_EQ(store->Get("m", 1)->stats.max_extent_m, 0.f);
  EXPECT_EQ(store->Get("m", 1)->training_set_bytes, 0u);  // none kept: it cannot grow
  NewModel next = Sample("m");
  next.training_set = {9, 9};
  next.feature_version = 3;
  next.stats.min_extent_m = 0.25f;
  next.stats.max_extent_m = 1.75f;
  ASSERT_TRUE(store->Put(next).ok());
  auto got = store->Get("m", 2);
  ASSERT_TRUE(got.ok());
  EXPECT_EQ(got->feature_version, 3u);
  EXPECT_EQ(got->stats.min_extent_m, 0.25f);
  EXPECT_EQ(got->stats.max_extent_m, 1.75f);
  EXPECT_EQ(got->training_set_bytes, 2u);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  EXPECT_NE(sqlite3_exec(db, "UPDATE versions SET description = 'x'", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
}

TEST(Store, NewerSchemaIsAClearStartupError) {
  TempDir dir;
  const std::string path = dir.file("new.db");
  { ASSERT_TRUE(OpenOk(path)); }
  RawExec(path, "PRAGMA user_version = 99;");
  auto store = ModelStore::Open(path);
  ASSERT_FALSE(store.ok());
  EXPECT_EQ(store.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_NE(store.error().message.find("newer"), std::string::npos) << store.error().message;
}

TEST(Store, GarbageFileIsAClearStartupError) {
  TempDir dir;
  const std::string path = dir.file("garbage.db");
  std::ofstream(path) << std::string(4096, 'x');
  auto store = ModelStore::Open(path);
  ASSERT_FALSE(store.ok());
  EXPECT_EQ(store.error().code, ErrorCode::kDataLoss);
  EXPECT_NE(store.error().message.find(path), std::string::npos) << store.error().message;
}

TEST(Store, ReadOnlyFileIsAClearStartupError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores file permissions";
  TempDir dir;
  const std::string path = dir.file("ro.db");
  { ASSERT_TRUE(OpenOk(path)); }
  ::chmod(path.c_str(), 0444);
  auto store = ModelStore::Open(path);
  ASSERT_FALSE(store.ok());
  EXPECT_EQ(store.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_NE(store.error().message.find("read-only"), std::string::npos) << store.error().message;
}

TEST(Store, ReadOnlyUriIsAClearStartupError) {  // the same check, reachable as root too
  TempDir dir;
  const std::string path = dir.file("ro2.db");
  { ASSERT_TRUE(OpenOk(path)); }
  auto store = ModelStore::Open("file:" + path + "?mode=ro");
  ASSERT_FALSE(store.ok());
  EXPECT_EQ(store.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_NE(store.error().message.find("read-only"), std::string::npos) << store.error().message;
}

// ---------------------------------------------------------------------------------------------
// ModelCache

NewModel Deserializable(const std::string& name, std::vector<std::string> categories) {
  NewModel m = Sample(name);
  Model model;
  model.categories = std::move(categories);
  model.methods = {MethodId::kBoK, MethodId::kFusion};
  m.blob = testing::FakeSerialize(model);
  return m;
}

TEST(ModelCache, LoadsOnceThenServesFromMemory) {
  auto store = OpenOk(":memory:");
  ASSERT_TRUE(store->Put(Deserializable("m", {"a", "b"})).ok());
  int calls = 0;
  ModelCache cache(*store, [&](std::span<const uint8_t> b) { ++calls; return testing::FakeDeserialize(b); });
  auto first = cache.Load("m", 0);
  ASSERT_TRUE(first.ok()) << first.error().message;
  EXPECT_EQ(first->model->categories, (std::vector<std::string>{"a", "b"}));
  auto again = cache.Load("m", 1);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->model.get(), first->model.get());
  EXPECT_EQ(again->load_ms, 0);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_EQ(cache.Load("nope", 0).error().code, ErrorCode::kNotFound);
}

TEST(ModelCache, EvictsTheLeastRecentlyUsedBeyondCapacity) {
  auto store = OpenOk(":memory:");
  for (const char* n : {"a", "b", "c"}) ASSERT_TRUE(store->Put(Deserializable(n, {"x", "y"})).ok());
  int calls = 0;
  ModelCache cache(*store, [&](std::span<const uint8_t> b) { ++calls; return testing::FakeDeserialize(b); }, 2);
  ASSERT_TRUE(cache.Load("a", 0).ok());
  ASSERT_TRUE(cache.Load("b", 0).ok());
  ASSERT_TRUE(cache.Load("a", 0).ok());  // a is now the most recent
  ASSERT_TRUE(cache.Load("c", 0).ok());  // evicts b
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_EQ(calls, 3);
  ASSERT_TRUE(cache.Load("a", 0).ok());
  EXPECT_EQ(calls, 3);
  ASSERT_TRUE(cache.Load("b", 0).ok());
  EXPECT_EQ(calls, 4);
}

TEST(ModelCache, SeesVersionsAndDeletesFromAnotherProcess) {
  TempDir dir;
  const std::string path = dir.file("shared.db");
  auto mine = OpenOk(path);
  auto theirs = OpenOk(path);  // another server on the same file
  ModelCache cache(*mine, testing::FakeDeserialize);
  ASSERT_TRUE(theirs->Put(Deserializable("m", {"a", "b"})).ok());
  auto v1 = cache.Load("m", 0);
  ASSERT_TRUE(v1.ok());
  EXPECT_EQ(v1->record.version, 1u);
  ASSERT_TRUE(theirs->Put(Deserializable("m", {"a", "b", "c"})).ok());
  auto v2 = cache.Load("m", 0);  // no restart needed
  ASSERT_TRUE(v2.ok());
  EXPECT_EQ(v2->record.version, 2u);
  EXPECT_EQ(v2->model->categories.size(), 3u);
  EXPECT_EQ(cache.size(), 2u);
  ASSERT_TRUE(theirs->Delete("m", 1).ok());
  EXPECT_EQ(cache.Load("m", 1).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(cache.size(), 1u);  // the deleted version's entry was dropped
}

// A store restored from another trainer's (model-sync.sh pull) starts its ids again: id 1 is then
// another blob, and the cache must serve the record's bytes, not what it held under that id.
TEST(ModelCache, AnIdWhoseBlobChangedIsLoadedAgain) {
  TempDir dir;
  const std::string path = dir.file("restored.db");
  auto store = OpenOk(path);
  ASSERT_TRUE(store->Put(Deserializable("m", {"a", "b"})).ok());
  int calls = 0;
  ModelCache cache(*store, [&](std::span<const uint8_t> b) { ++calls; return testing::FakeDeserialize(b); });
  auto before = cache.Load("m", 0);
  ASSERT_TRUE(before.ok());
  EXPECT_EQ(before->model->categories.size(), 2u);
  {  // what a restore leaves: the same id, another blob (and its digest)
    Model other;
    other.categories = {"a", "b", "c"};
    other.methods = {MethodId::kBoK, MethodId::kFusion};
    const std::vector<uint8_t> blob = testing::FakeSerialize(other);
    std::string hex;
    for (uint8_t b : blob) {
      static const char* digits = "0123456789abcdef";
      hex += digits[b >> 4], hex += digits[b & 15];
    }
    RawExec(path, "DROP TRIGGER versions_immutable; UPDATE versions SET blob = x'" + hex + "', sha256 = '" + Sha256Hex(blob) + "' WHERE id = " +
                      std::to_string(before->record.id) + ";");
  }
  auto after = cache.Load("m", 0);
  ASSERT_TRUE(after.ok()) << after.error().message;
  EXPECT_EQ(after->record.id, before->record.id);
  EXPECT_EQ(after->model->categories.size(), 3u);
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(cache.size(), 1u);
}

TEST(ModelCache, UndeserializableBlobIsAnErrorNotACrash) {
  auto store = OpenOk(":memory:");
  NewModel garbage = Sample("m");
  garbage.blob = {'n', 'o', 'p', 'e'};
  ASSERT_TRUE(store->Put(garbage).ok());
  ModelCache cache(*store, testing::FakeDeserialize);
  auto r = cache.Load("m", 0);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kDataLoss);
  EXPECT_NE(r.error().message.find("'m' version 1"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace glimpse::server
