// StreamClassify's domain logic, outside the service class: the first chunk opens a scan session (its
// model, method and operating point), later chunks must agree with it, each chunk is fused and answered
// with the evolving decision, and the end of the scan is answered with Classify's decision of all of it.
// A tracking stream (ScanChunk.track) sends whole frames: each is split into objects, and only the
// target's points are fused.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "glimpse/session/scene_tracking.h"

#include "engine.h"
#include "limits.h"
#include "log.h"
#include "model_cache.h"

namespace glimpse::server {

class ScanStream {
 public:
  // `log` names the model, the method and the points as the chunks arrive; it outlives the stream.
  ScanStream(ModelCache& cache, const Engine& engine, const Limits& limits, SteadyClock clock, RequestLog& log);

  // The decision after chunk `index` (the message's place in the stream; an empty chunk repeats the
  // last decision, e.g. a first chunk that only names the model). Errors name the chunk.
  Expected<v1::Decision> Add(const v1::ScanChunk& chunk, uint64_t index);
  // The scanner is done: Classify's decision of the whole scan, answering chunk `last_index`.
  // INVALID_ARGUMENT for a stream that ended before its first chunk or a scan that gave no decision.
  Expected<v1::Decision> Finish(uint64_t last_index);

 private:
  Status Open(const v1::ScanChunk& first);
  // Only the first chunk chooses the model, method and operating point; later ones may repeat them.
  Status CheckSameSession(const v1::ScanChunk& chunk, uint64_t index) const;
  v1::Decision Reply(const StreamDecision& decision, uint64_t index,
                     std::chrono::steady_clock::time_point start) const;
  // A tracking stream's frame: the target's points fused, or the last decision repeated when the
  // frame does not show it; either way the reply says where the target is.
  Expected<v1::Decision> AddFrame(const Cloud& frame, uint64_t index, std::chrono::steady_clock::time_point start);

  ModelCache& cache_;
  const Engine& engine_;
  const Limits& limits_;
  SteadyClock clock_;
  RequestLog& log_;
  std::unique_ptr<ScanSession> session_;  // opened by the first chunk
  LoadedModel model_;
  MethodId method_ = MethodId::kFusion;  // resolved: the model's default when none was asked
  double known_acceptance_ = 0;
  std::optional<SceneTracker> tracker_;  // set by a first chunk that names a target
};

}  // namespace glimpse::server
