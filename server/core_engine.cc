// The real Engine: glimpse::train/classify/serialize/deserialize and ScanSession::create, with the
// Train header's parameters mapped onto core's TrainParams by the wire library (unset fields keep core's
// defaults).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <optional>

#include "engine.h"
#include "glimpse/clock.h"
#include "glimpse/learning/training_set.h"
#include "proto/wire/train_params.h"

namespace glimpse::server {

namespace {

// Trains on the clouds, joined with the base's kept set when its bytes are given, learning from the base
// model's heads (engine.h); the set's bytes come back when at most keep_set_bytes.
Expected<TrainedModel> TrainJoined(const std::vector<TrainingCloud>& data, const TrainParams& params,
                                   std::span<const uint8_t> base_set, std::span<const uint8_t> base_model,
                                   size_t keep_set_bytes, const ProgressFn& progress, const CancelFn& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<TrainingSet> base;
  if (!base_set.empty()) {
    auto read = deserialize_training_set(base_set);
    if (!read) return Error{read.error().code, "the base's training set: " + read.error().message};
    base = std::move(*read);
  }
  std::optional<Model> start;  // where a grown model's learning starts
  if (!base_model.empty()) {
    auto read = deserialize(base_model);
    if (!read) return Error{read.error().code, "the base model: " + read.error().message};
    start = std::move(*read);
  }
  auto set = training_set(data, params, progress, cancel, base ? &*base : nullptr);
  if (!set) return set.error();
  if (base) {
    auto joined = join(std::move(*base), std::move(*set));
    if (!joined) return joined.error();
    set = std::move(*joined);
  }
  TrainedModel out;
  if (keep_set_bytes > 0) {
    out.training_set = serialize(*set);
    if (out.training_set.size() > keep_set_bytes) out.training_set.clear();
  }
  auto model = glimpse::train(std::move(*set), params, progress, cancel, start ? &*start : nullptr);
  if (!model) return model.error();
  out.model = std::move(*model);
  out.model.stats.seconds = ms_since(t0) / 1000.0;  // the added clouds' features and the learning
  return out;
}

}  // namespace

Engine CoreEngine(int request_threads) {
  // OpenMP's thread count is a per-thread setting: set on the gRPC thread that runs the call, it
  // bounds core's parallel loops for this call only.
  auto budget = [request_threads] {
    if (request_threads > 0) omp_set_num_threads(request_threads);
  };
  Engine e;
  e.train = [budget](const std::vector<TrainingCloud>& data, const wire::TrainSpec& spec,
                     std::span<const uint8_t> base_set, std::span<const uint8_t> base_model, size_t keep_set_bytes,
                     const ProgressFn& progress, const CancelFn& cancel) -> Expected<TrainedModel> {
    auto params = wire::ToTrainParams(spec);
    if (!params) return params.error();
    budget();
    return TrainJoined(data, *params, base_set, base_model, keep_set_bytes, progress, cancel);
  };
  e.classify = [budget](const Model& model, const Cloud& cloud, std::optional<MethodId> method,
                        const CancelFn& cancel) {
    budget();
    return glimpse::classify(model, cloud, method, cancel);
  };
  e.classify_batch = [budget](const Model& model, std::span<const Cloud> clouds, std::optional<MethodId> method,
                              const CancelFn& cancel) {
    budget();
    // One thread per cloud: whole clouds in parallel waste less than threads sharing one cloud's
    // serial parts. Results go to their own slots, so they do not depend on the thread count.
    std::vector<Expected<Classification>> out(clouds.size(), cancelled("the call was cancelled before this cloud"));
    const int threads = std::max(1, std::min(omp_get_max_threads(), static_cast<int>(clouds.size())));
    const int inner = std::max(1, omp_get_max_threads() / threads);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int64_t i = 0; i < static_cast<int64_t>(clouds.size()); ++i) {
      omp_set_num_threads(inner);
      if (cancel && cancel()) continue;
      out[static_cast<size_t>(i)] = glimpse::classify(model, clouds[static_cast<size_t>(i)], method, cancel);
    }
    return out;
  };
  e.effective_parameters = [](const wire::TrainSpec& spec) -> Expected<v1::TrainParameters> {
    auto params = wire::ToTrainParams(spec);
    if (!params) return params.error();
    return wire::FromTrainParams(*params);
  };
  e.set_known_acceptance = [](const Model& model, Classification& c, double known_acceptance) {
    return glimpse::set_known_acceptance(model, c, known_acceptance);
  };
  e.serialize = [](const Model& model) { return glimpse::serialize(model); };
  e.deserialize = [](std::span<const uint8_t> bytes) { return glimpse::deserialize(bytes); };
  e.segment_scene = [budget](const Cloud& frame, const SceneParams& params) {
    budget();
    return glimpse::segment_scene(frame, params);
  };
  e.create_session = [](std::shared_ptr<const Model> model, const SessionParams& params) {
    return ScanSession::create(std::move(model), params);
  };
  return e;
}

}  // namespace glimpse::server
