// The real Engine: glimpse::train/classify/serialize/deserialize and ScanSession::create, with the
// Train header's parameters mapped onto core's TrainParams by the wire library (unset fields keep core's
// defaults).
#include <omp.h>

#include <algorithm>

#include "engine.h"
#include "proto/wire/train_params.h"

namespace glimpse::server {

Engine CoreEngine(int request_threads) {
  // OpenMP's thread count is a per-thread setting: set on the gRPC thread that runs the call, it
  // bounds core's parallel loops for this call only.
  auto budget = [request_threads] {
    if (request_threads > 0) omp_set_num_threads(request_threads);
  };
  Engine e;
  e.train = [budget](const std::vector<TrainingCloud>& data, const wire::TrainSpec& spec, const ProgressFn& progress,
                     const CancelFn& cancel) -> Expected<Model> {
    auto params = wire::ToTrainParams(spec);
    if (!params) return params.error();
    budget();
    return glimpse::train(data, *params, progress, cancel);
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
  e.create_session = [](std::shared_ptr<const Model> model, const SessionParams& params) {
    return ScanSession::create(std::move(model), params);
  };
  return e;
}

}  // namespace glimpse::server
