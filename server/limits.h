// Server limits (defaults in one place) and the registry that admits streams up to a concurrency
// limit and cancels the ones that outlive the stream duration limit.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <mutex>

#include "glimpse/expected.h"

namespace glimpse::server {

struct Limits {
  size_t max_message_bytes = 64u << 20;       // gRPC receive/send limit per message
  size_t max_points_per_cloud = 1'000'000;    // per cloud, chunk or training cloud; summed over a batch
  size_t max_batch_clouds = 256;              // clouds per ClassifyBatch call
  size_t max_concurrent_streams = 64;         // Train + StreamClassify calls at once
  std::chrono::seconds max_stream_duration{600};  // StreamClassify, and Train while receiving
  size_t max_train_clouds = 100'000;          // per Train call
  size_t max_train_points = 50'000'000;       // summed over a Train call's clouds (~600 MB)
  size_t max_session_points = 1'000'000;      // accumulated in one StreamClassify session
  size_t max_session_chunks = 10'000;
  size_t max_cached_models = 16;              // deserialized models kept in memory
  // The largest training set kept beside a trained model, compressed (every row's features: about
  // 1.2 KB a row with the default methods, 56 MiB for 272 meshes with the recipe), so the model can
  // grow (TrainHeader.base); 0: none kept.
  size_t max_training_set_bytes = 256u << 20;
};

using SteadyClock = std::function<std::chrono::steady_clock::time_point()>;

inline double MsSince(std::chrono::steady_clock::time_point start, std::chrono::steady_clock::time_point now) {
  return std::chrono::duration<double, std::milli>(now - start).count();
}

class StreamRegistry {
 public:
  StreamRegistry(size_t max_streams, std::chrono::steady_clock::duration max_duration, SteadyClock clock);

  // A slot held by one stream; released on destruction.
  class Ticket {
   public:
    Ticket(Ticket&& other) noexcept : registry_(other.registry_), id_(other.id_) { other.registry_ = nullptr; }
    Ticket& operator=(Ticket&&) = delete;
    ~Ticket();
    bool expired() const;   // the watchdog cancelled the stream for running too long
    bool over_time() const;  // armed and older than the limit (checked at every message)
    void disarm();         // from now on, no duration limit (Train once all clouds are in)

   private:
    friend class StreamRegistry;
    Ticket(StreamRegistry* r, uint64_t id) : registry_(r), id_(id) {}
    StreamRegistry* registry_;
    uint64_t id_;
  };

  // RESOURCE_EXHAUSTED when max_streams are open. `cancel` stops the stream (ServerContext::TryCancel).
  Expected<Ticket> Admit(std::function<void()> cancel);
  // Cancels armed streams older than max_duration; returns how many. Called by a watchdog thread for
  // streams that sit idle (a stream that keeps sending is stopped at its next message instead, with
  // RESOURCE_EXHAUSTED; a cancelled one only tells its client CANCELLED).
  size_t Reap();
  size_t active() const;

 private:
  struct Slot {
    std::function<void()> cancel;
    std::chrono::steady_clock::time_point start;
    bool armed = true;
    bool expired = false;
  };
  size_t max_streams_;
  std::chrono::steady_clock::duration max_duration_;
  SteadyClock clock_;
  mutable std::mutex mutex_;
  uint64_t next_id_ = 0;
  std::map<uint64_t, Slot> slots_;
};

}  // namespace glimpse::server
