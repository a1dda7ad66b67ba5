#include "limits.h"


namespace glimpse::server {

StreamRegistry::StreamRegistry(size_t max_streams, std::chrono::steady_clock::duration max_duration,
                               SteadyClock clock)
    : max_streams_(max_streams), max_duration_(max_duration), clock_(std::move(clock)) {
  if (!clock_) clock_ = [] { return std::chrono::steady_clock::now(); };
}

Expected<StreamRegistry::Ticket> StreamRegistry::Admit(std::function<void()> cancel) {
  std::lock_guard lock(mutex_);
  if (slots_.size() >= max_streams_)
    return resource_exhausted("too many concurrent streams (limit " + std::to_string(max_streams_) + ")");
  uint64_t id = next_id_++;
  slots_.emplace(id, Slot{std::move(cancel), clock_(), true, false});
  return Ticket(this, id);
}

size_t StreamRegistry::Reap() {
  // Cancels under the lock: a slot's ServerContext lives until its Ticket is destroyed, which takes
  // this lock, so a context is never cancelled after its call returned. TryCancel does not call back.
  std::lock_guard lock(mutex_);
  const auto now = clock_();
  size_t cancelled = 0;
  for (auto& [id, slot] : slots_) {
    if (slot.armed && !slot.expired && now - slot.start > max_duration_) {
      slot.expired = true;
      if (slot.cancel) slot.cancel();
      ++cancelled;
    }
  }
  return cancelled;
}

size_t StreamRegistry::active() const {
  std::lock_guard lock(mutex_);
  return slots_.size();
}

StreamRegistry::Ticket::~Ticket() {
  if (!registry_) return;
  std::lock_guard lock(registry_->mutex_);
  registry_->slots_.erase(id_);
}

bool StreamRegistry::Ticket::expired() const {
  std::lock_guard lock(registry_->mutex_);
  auto it = registry_->slots_.find(id_);
  return it != registry_->slots_.end() && it->second.expired;
}

bool StreamRegistry::Ticket::over_time() const {
  std::lock_guard lock(registry_->mutex_);
  auto it = registry_->slots_.find(id_);
  return it != registry_->slots_.end() && it->second.armed &&
         registry_->clock_() - it->second.start > registry_->max_duration_;
}

void StreamRegistry::Ticket::disarm() {
  std::lock_guard lock(registry_->mutex_);
  if (auto it = registry_->slots_.find(id_); it != registry_->slots_.end()) it->second.armed = false;
}

}  // namespace glimpse::server
