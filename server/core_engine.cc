// The real Engine: glimpse::train/classify/serialize/deserialize and ScanSession::create, with the
// Train header's parameters mapped onto core's TrainParams (unset fields keep core's defaults).
#include <omp.h>

#include <algorithm>
#include <limits>

#include "engine.h"
#include "glimpse/learning/train_params.h"

namespace glimpse::server {
namespace {

Expected<int> ToInt(uint32_t v, const char* field) {
  if (v > static_cast<uint32_t>(std::numeric_limits<int>::max())) return invalid_argument(std::string(field) + " is too large");
  return static_cast<int>(v);
}

}  // namespace

Expected<TrainParams> ToTrainParams(const TrainSpec& spec) {
  TrainParams params;
  if (!spec.methods.empty()) params.methods = spec.methods;
  if (spec.default_method) {
    params.default_method = *spec.default_method;
  } else if (std::find(params.methods.begin(), params.methods.end(), params.default_method) == params.methods.end()) {
    params.default_method = params.methods.front();  // core's default (fusion) was not asked for
  }
  const v1::TrainParameters& p = spec.parameters;
  if (p.has_support_radius_m()) params.features.surface.support_radius_m = static_cast<float>(p.support_radius_m());
  struct IntField {
    bool has;
    uint32_t value;
    const char* name;
    int* target;
  };
  const IntField fields[] = {
      {p.has_bok_codebook_size(), p.bok_codebook_size(), "bok_codebook_size", &params.bok_clusters},
      {p.has_bog_keypoint_clusters(), p.bog_keypoint_clusters(), "bog_keypoint_clusters", &params.bog_keypoint_clusters},
      {p.has_bog_volume_clusters(), p.bog_volume_clusters(), "bog_volume_clusters", &params.bog_volume_clusters},
      {p.has_bog_pca_dims(), p.bog_pca_dims(), "bog_pca_dims", &params.bog_pca_dims},
      {p.has_kgh_keypoint_clusters(), p.kgh_keypoint_clusters(), "kgh_keypoint_clusters", &params.kgh_clusters},
      {p.has_kgh_distance_bins(), p.kgh_distance_bins(), "kgh_distance_bins", &params.kgh_distance_bins},
      {p.has_centres_per_category(), p.centres_per_category(), "centres_per_category",
       &params.decision.centres_per_category},
      {p.has_neighbours(), p.neighbours(), "neighbours", &params.decision.neighbours},
  };
  for (const IntField& f : fields) {
    if (!f.has) continue;
    auto v = ToInt(f.value, f.name);
    if (!v) return v.error();
    *f.target = *v;
  }
  switch (p.decision()) {
    case v1::DECISION_KIND_NEAREST_CENTRE: params.decision.kind = DecisionRule::kNearestCentre; break;
    case v1::DECISION_KIND_NEAREST_NEIGHBOURS: params.decision.kind = DecisionRule::kNearestNeighbours; break;
    case v1::DECISION_KIND_CENTRES: params.decision.kind = DecisionRule::kCentres; break;
    case v1::DECISION_KIND_NEAREST_REFERENCE: params.decision.kind = DecisionRule::kNearestReference; break;
    default: break;  // unspecified: core's default
  }
  if (p.has_seed()) params.seed = p.seed();
  if (p.has_normalise_histograms()) params.normalise_histograms = p.normalise_histograms();
  if (p.has_filter_scans()) params.filter_scans = p.filter_scans();
  return params;
}

v1::TrainParameters FromTrainParams(const TrainParams& params) {
  v1::TrainParameters p;
  p.set_support_radius_m(params.features.surface.support_radius_m);
  p.set_bok_codebook_size(static_cast<uint32_t>(params.bok_clusters));
  p.set_bog_keypoint_clusters(static_cast<uint32_t>(params.bog_keypoint_clusters));
  p.set_bog_volume_clusters(static_cast<uint32_t>(params.bog_volume_clusters));
  p.set_bog_pca_dims(static_cast<uint32_t>(params.bog_pca_dims));
  p.set_kgh_keypoint_clusters(static_cast<uint32_t>(params.kgh_clusters));
  p.set_kgh_distance_bins(static_cast<uint32_t>(params.kgh_distance_bins));
  switch (params.decision.kind) {
    case DecisionRule::kNearestCentre: p.set_decision(v1::DECISION_KIND_NEAREST_CENTRE); break;
    case DecisionRule::kCentres: p.set_decision(v1::DECISION_KIND_CENTRES); break;
    case DecisionRule::kNearestNeighbours: p.set_decision(v1::DECISION_KIND_NEAREST_NEIGHBOURS); break;
    case DecisionRule::kNearestReference: p.set_decision(v1::DECISION_KIND_NEAREST_REFERENCE); break;
  }
  p.set_seed(params.seed);
  p.set_centres_per_category(static_cast<uint32_t>(params.decision.centres_per_category));
  p.set_neighbours(static_cast<uint32_t>(params.decision.neighbours));
  p.set_normalise_histograms(params.normalise_histograms);
  p.set_filter_scans(params.filter_scans);
  return p;
}

Engine CoreEngine(int request_threads) {
  // OpenMP's thread count is a per-thread setting: set on the gRPC thread that runs the call, it
  // bounds core's parallel loops for this call only.
  auto budget = [request_threads] {
    if (request_threads > 0) omp_set_num_threads(request_threads);
  };
  Engine e;
  e.train = [budget](const std::vector<TrainingCloud>& data, const TrainSpec& spec, const ProgressFn& progress,
                     const CancelFn& cancel) -> Expected<Model> {
    auto params = ToTrainParams(spec);
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
  e.effective_parameters = [](const TrainSpec& spec) -> Expected<v1::TrainParameters> {
    auto params = ToTrainParams(spec);
    if (!params) return params.error();
    return FromTrainParams(*params);
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
