#include "model_cache.h"

#include <chrono>
#include <unordered_set>

namespace glimpse::server {

ModelCache::ModelCache(ModelStore& store, std::function<Expected<Model>(std::span<const uint8_t>)> deserialize,
                       size_t capacity)
    : store_(store), deserialize_(std::move(deserialize)), capacity_(capacity == 0 ? 1 : capacity) {}

size_t ModelCache::size() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

void ModelCache::Forget(int64_t id) {
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(id); it != entries_.end()) {
    lru_.erase(it->second.lru);
    entries_.erase(it);
  }
}

void ModelCache::SweepIfChanged(bool force) {
  int64_t now = store_.DataVersion();
  {
    std::lock_guard lock(mutex_);
    if (!force && (now == data_version_ || entries_.empty())) {
      data_version_ = now;
      return;
    }
  }
  auto ids = store_.Ids();
  if (!ids) return;  // keep the entries; the next call tries again
  std::unordered_set<int64_t> live(ids->begin(), ids->end());
  std::lock_guard lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (live.count(it->first)) {
      ++it;
    } else {
      lru_.erase(it->second.lru);
      it = entries_.erase(it);
    }
  }
  data_version_ = now;
}

Expected<LoadedModel> ModelCache::Load(std::string_view name, uint32_t version) {
  SweepIfChanged();
  auto record = store_.Get(name, version);
  if (!record) return record.error();
  const int64_t id = record->id;
  {
    std::lock_guard lock(mutex_);
    if (auto it = entries_.find(id); it != entries_.end()) {
      // An id names one blob only within one store's lineage: a store restored from another trainer's
      // (model-sync.sh pull) starts its ids again, so the entry must hold the record's very bytes.
      if (it->second.sha256 == record->sha256) {
        lru_.splice(lru_.begin(), lru_, it->second.lru);
        return LoadedModel{std::move(*record), it->second.model, 0};
      }
      lru_.erase(it->second.lru);
      entries_.erase(it);
    }
  }
  // Miss: read and deserialize outside the lock, so one slow load does not stall cached models.
  const auto start = std::chrono::steady_clock::now();
  auto blob = store_.Blob(id);
  if (!blob) return blob.error();
  auto model = deserialize_(*blob);
  if (!model) {
    Error e = model.error();
    return Error{e.code, "model '" + record->name + "' version " + std::to_string(record->version) + ": " + e.message};
  }
  auto shared = std::make_shared<const Model>(std::move(*model));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(id); it != entries_.end()) {
    if (it->second.sha256 == record->sha256) {  // another thread loaded it meanwhile
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      return LoadedModel{std::move(*record), it->second.model, ms};
    }
    lru_.erase(it->second.lru);  // another blob under this id: ours is the record's
    entries_.erase(it);
  }
  lru_.push_front(id);
  entries_.emplace(id, Entry{shared, lru_.begin(), record->sha256});
  while (entries_.size() > capacity_) {
    entries_.erase(lru_.back());
    lru_.pop_back();
  }
  return LoadedModel{std::move(*record), std::move(shared), ms};
}

}  // namespace glimpse::server
