// ModelCache: resolves a model reference through the store on every call (so versions and default
// pins written by other processes are seen at once) and keeps deserialized models in memory, keyed by
// the version's id, which is never reused. Entries of versions deleted anywhere are dropped when the
// database's data_version moves; the least recently used entries go beyond `capacity`.
#pragma once

#include <cstdint>
#include <list>
#include <string>
#include <memory>
#include <mutex>
#include <string_view>
#include <unordered_map>

#include "engine.h"
#include "store.h"

namespace glimpse::server {

struct LoadedModel {
  ModelRecord record;
  std::shared_ptr<const Model> model;
  double load_ms = 0;  // 0 when it came from the cache
};

class ModelCache {
 public:
  ModelCache(ModelStore& store, std::function<Expected<Model>(std::span<const uint8_t>)> deserialize,
             size_t capacity = 16);

  // version 0: the name's default version.
  Expected<LoadedModel> Load(std::string_view name, uint32_t version);
  void Forget(int64_t id);
  // Drops entries whose versions no longer exist (call after a delete through this connection,
  // which data_version does not report).
  void Sweep() { SweepIfChanged(true); }
  size_t size() const;

 private:
  void SweepIfChanged(bool force = false);

  ModelStore& store_;
  std::function<Expected<Model>(std::span<const uint8_t>)> deserialize_;
  size_t capacity_;
  mutable std::mutex mutex_;
  int64_t data_version_ = -1;
  std::list<int64_t> lru_;  // front: most recently used
  struct Entry {
    std::shared_ptr<const Model> model;
    std::list<int64_t>::iterator lru;
    std::string sha256;  // the blob's: an id alone names another blob in a restored store
  };
  std::unordered_map<int64_t, Entry> entries_;
};

}  // namespace glimpse::server
