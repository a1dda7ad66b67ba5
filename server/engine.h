// The core functions the service calls, held as values so tests can hand in fakes (and so everything
// but core_engine.cc builds without the recogniser). CoreEngine() returns the real glimpse:: ones.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "glimpse/geometry/scene.h"
#include "glimpse/learning/model.h"
#include "glimpse/session/session.h"
#include "glimpse/v1/glimpse.pb.h"
#include "proto/wire/train_params.h"

namespace glimpse::server {

// A trained model and the bytes of the training set it learnt from (empty: none kept).
struct TrainedModel {
  Model model;
  std::vector<uint8_t> training_set;
};

struct Engine {
  // Trains on the clouds, joined with a base version's training set when its bytes are given (the
  // model grows: only the clouds' features are computed, and learning starts from the base model, whose
  // bytes come beside them). The set's bytes come back with the model when they are at most
  // `keep_set_bytes` (0: none kept).
  std::function<Expected<TrainedModel>(const std::vector<TrainingCloud>&, const wire::TrainSpec&,
                                       std::span<const uint8_t> base_set, std::span<const uint8_t> base_model,
                                       size_t keep_set_bytes, const ProgressFn&, const CancelFn&)>
      train;
  std::function<Expected<Classification>(const Model&, const Cloud&, std::optional<MethodId>,
                                         const CancelFn&)>
      classify;
  // Several clouds with one model: one result per cloud, in order, each what classify gives for it
  // alone (whatever the thread count). Clouds left when the CancelFn fires are kCancelled.
  std::function<std::vector<Expected<Classification>>(const Model&, std::span<const Cloud>, std::optional<MethodId>,
                                                      const CancelFn&)>
      classify_batch;
  // Re-decides "unknown" of a classification at a request's operating point (known acceptance in
  // (0, 1]; 0: the model's default); winner and scores stay. Empty: every answer stays at the default.
  std::function<Status(const Model&, Classification&, double)> set_known_acceptance;
  std::function<std::vector<uint8_t>(const Model&)> serialize;
  std::function<Expected<Model>(std::span<const uint8_t>)> deserialize;
  // The planes and objects of a scanner's frame (core's segment_scene). Empty: ClassifyScene and
  // tracking streams are UNIMPLEMENTED.
  std::function<Expected<Scene>(const Cloud&, const SceneParams&)> segment_scene;
  std::function<Expected<std::unique_ptr<ScanSession>>(std::shared_ptr<const Model>, const SessionParams&)>
      create_session;
  // The parameters a spec trains with, every field set: the request's where it gave them, the
  // recogniser's defaults elsewhere (ModelInfo.parameters). Empty: the request's are stored as given.
  std::function<Expected<v1::TrainParameters>(const wire::TrainSpec&)> effective_parameters;
};

// The real recogniser (core_engine.cc, target glimpse_server_engine). Each call computes with
// `request_threads` threads (0: OpenMP's default for the calling thread); a batch spreads its clouds
// over them, one thread per cloud.
Engine CoreEngine(int request_threads = 0);

}  // namespace glimpse::server
