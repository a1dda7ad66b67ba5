// train() (model.h): the features of every training cloud, whole and as its top-down prefixes, computed in
// parallel into a training set (training_set.h), then train_on_features (training.cpp) learns from them.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "glimpse/clock.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/learning/training.h"
#include "glimpse/learning/training_set.h"
#include "glimpse/random.h"
#include "glimpse/threads.h"
#include "glimpse/views/exploration.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/sampling.h"
#include "learning/training_checks.h"

namespace glimpse {

Cloud training_view(const Cloud& cloud, const TrainParams& params, uint64_t salt) {
  if (!(params.tilt_deg > 0)) return cloud;
  return rotate_about_centroid(cloud, random_tilt(splitmix64(params.seed, salt), params.tilt_deg));
}

namespace {

// One cloud to learn: a training cloud whole (prefix 0) or its top `prefix` points.
struct Job {
  size_t cloud;
  size_t prefix;
};

// The clouds to learn from: each training cloud whole, then its top-down prefixes; `learnt` receives each
// training cloud as it is learnt (training_view). `seen`: the views of each object before these.
std::vector<Job> learning_jobs(const std::vector<TrainingCloud>& data, const TrainParams& params,
                               std::map<std::string, uint64_t> seen, std::vector<Cloud>& learnt) {
  std::vector<Job> jobs;
  learnt.assign(data.size(), Cloud{});
  for (size_t i = 0; i < data.size(); ++i) {
    // The tilt is seeded by the object's name and the cloud's place among its views, not by its
    // place in the list: the same views learnt anywhere (the lab, the service) get the same tilts.
    const uint64_t salt = data[i].object_id.empty() ? i : object_seed(params.seed, data[i].object_id) + seen[data[i].object_id]++;
    learnt[i] = training_view(data[i].cloud, params, salt);
    jobs.push_back({i, 0});
    const size_t n = data[i].cloud.points.size();
    if (data[i].augmented && !params.augmented_prefixes) continue;
    for (double f : params.partial_prefixes) {
      const auto count = static_cast<size_t>(std::lround(f * static_cast<double>(n)));
      if (count >= params.features.min_points && count < n) jobs.push_back({i, count});
    }
  }
  return jobs;
}

// Every job's features, in parallel; batches keep progress and cancel responsive. `tilted`: the clouds
// learnt are turned, and `as_seen` receives the features of the clouds as given, what calibration
// decides (what a sensor sends).
Status job_features(const std::vector<TrainingCloud>& data, const std::vector<Cloud>& learnt,
                    const std::vector<Job>& jobs, const TrainParams& params, bool tilted,
                    std::vector<Expected<CloudFeatures>>& feats, std::vector<Expected<CloudFeatures>>& as_seen,
                    const ProgressFn& progress, const CancelFn& cancel) {
  const std::vector<MethodId> base = base_methods(params);
  const int threads = resolve_threads(params.threads);
  feats.assign(jobs.size(), internal_error("not computed"));
  as_seen.assign(tilted ? jobs.size() : 0, internal_error("not computed"));
  const MethodFeatureParams as_given = method_feature_params(params);
  MethodFeatureParams learnt_only = as_given;
  learnt_only.top_prefix_fraction = 0;
  const size_t batch = static_cast<size_t>(threads) * 4;
  for (size_t begin = 0; begin < jobs.size(); begin += batch) {
    if (cancel && cancel()) return cancelled("training cancelled");
    const int64_t end = static_cast<int64_t>(std::min(jobs.size(), begin + batch));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int64_t j = static_cast<int64_t>(begin); j < end; ++j) {
      auto features_of = [&](const Cloud& cloud, const MethodFeatureParams& p) {
        return jobs[j].prefix ? cloud_features(reveal_top_down(cloud, jobs[j].prefix), p, base, 1, cancel)
                              : cloud_features(cloud, p, base, 1, cancel);
      };
      // Tilted, calibration decides the clouds as given: only they need the novelty's top-down prefix.
      feats[j] = features_of(learnt[jobs[j].cloud], tilted ? learnt_only : as_given);
      if (tilted) as_seen[j] = features_of(data[jobs[j].cloud].cloud, as_given);
    }
    if (progress) progress({"features", static_cast<size_t>(end), jobs.size()});
  }
  return {};
}

// The jobs' features as samples to learn from. A whole cloud must work; a prefix too small or too thin
// for a method is only skipped.
Expected<std::vector<TrainingSample>> training_samples(const std::vector<TrainingCloud>& data,
                                                       const std::vector<Job>& jobs,
                                                       std::vector<Expected<CloudFeatures>>& feats,
                                                       std::vector<Expected<CloudFeatures>>& as_seen, bool tilted) {
  std::vector<TrainingSample> samples;
  samples.reserve(jobs.size());
  for (size_t j = 0; j < jobs.size(); ++j) {
    const TrainingCloud& d = data[jobs[j].cloud];
    if (!feats[j].ok()) {
      if (jobs[j].prefix && feats[j].error().code == ErrorCode::kInvalidArgument) continue;
      return Error{feats[j].error().code, "training cloud " + std::to_string(jobs[j].cloud) + " (category '" +
                                              d.category + "', object '" + d.object_id + "')" +
                                              (jobs[j].prefix ? ", top " + std::to_string(jobs[j].prefix) + " points" : "") +
                                              ": " + feats[j].error().message};
    }
    samples.push_back({d.category, d.object_id, std::move(*feats[j]), jobs[j].prefix == 0, std::nullopt, d.augmented});
    if (tilted && as_seen[j].ok()) samples.back().as_seen = std::move(*as_seen[j]);
  }
  return samples;
}

// Each cloud as given, with its relative density (what the scan filters' density is the median of).
std::vector<GivenCloud> given_clouds(const std::vector<TrainingCloud>& data, const TrainParams& params) {
  std::vector<GivenCloud> given(data.size());
  const int threads = resolve_threads(params.threads);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
  for (int64_t i = 0; i < static_cast<int64_t>(data.size()); ++i) {
    const TrainingCloud& d = data[static_cast<size_t>(i)];
    given[static_cast<size_t>(i)] = {d.category, d.object_id, relative_density(d.cloud.points), d.augmented};
  }
  return given;
}

// The parameters learnt with: the density clouds are classified at, when the scan filters need one and
// none is given, is the median relative density of the training clouds as given.
TrainParams with_learnt_density(const std::vector<GivenCloud>& clouds, const TrainParams& params) {
  TrainParams learnt_params = params;
  if (params.filter_scans && params.filters.relative_density <= 0) {
    std::vector<double> density;
    for (const GivenCloud& c : clouds)
      if (c.relative_density != 0.0) density.push_back(c.relative_density);
    if (!density.empty()) {
      std::nth_element(density.begin(), density.begin() + std::ptrdiff_t(density.size() / 2), density.end());
      learnt_params.filters.relative_density = density[density.size() / 2];
    }
  }
  return learnt_params;
}

// The rows in the order they are learnt: by category, then object, each object's rows as they came.
void order_by_object(std::vector<TrainingSample>& samples) {
  std::stable_sort(samples.begin(), samples.end(), [](const TrainingSample& a, const TrainingSample& b) {
    return std::tie(a.category, a.object_id) < std::tie(b.category, b.object_id);
  });
}

// Statistics count the clouds given, not the prefixes made of them.
void count_given_clouds(Model& model, const std::vector<GivenCloud>& clouds) {
  model.stats.clouds = clouds.size();
  std::fill(model.stats.clouds_per_category.begin(), model.stats.clouds_per_category.end(), 0);
  for (const GivenCloud& c : clouds)
    ++model.stats.clouds_per_category[static_cast<size_t>(
        std::find(model.categories.begin(), model.categories.end(), c.category) - model.categories.begin())];
}

}  // namespace

Expected<TrainingSet> training_set(const std::vector<TrainingCloud>& data, const TrainParams& params,
                                   const ProgressFn& progress, const CancelFn& cancel, const TrainingSet* base) {
  if (data.empty()) return invalid_argument("no training clouds");
  std::vector<GivenCloud> categories = base ? base->clouds : std::vector<GivenCloud>{};
  for (const TrainingCloud& d : data) categories.push_back({d.category, {}, 0, false});
  if (Status s = check_training_set(categories, params); !s.ok()) return s.error();  // before any feature
  std::map<std::string, uint64_t> seen;  // views so far per object: the base's
  if (base)
    for (const GivenCloud& c : base->clouds) ++seen[c.object_id];
  std::vector<Cloud> learnt;
  const std::vector<Job> jobs = learning_jobs(data, params, std::move(seen), learnt);
  // Tilted training views: the clouds as given are what calibration decides (what a sensor sends).
  const bool tilted = params.tilt_deg > 0 && params.calibration_folds >= 2;
  std::vector<Expected<CloudFeatures>> feats, as_seen;
  if (Status s = job_features(data, learnt, jobs, params, tilted, feats, as_seen, progress, cancel); !s.ok())
    return s.error();
  auto samples = training_samples(data, jobs, feats, as_seen, tilted);
  if (!samples.ok()) return samples.error();
  return TrainingSet{kFeaturePipelineVersion, given_clouds(data, params), std::move(*samples)};
}

Expected<Model> train(TrainingSet set, const TrainParams& params, const ProgressFn& progress, const CancelFn& cancel,
                      const Model* start) {
  const auto t0 = std::chrono::steady_clock::now();
  if (set.feature_version != kFeaturePipelineVersion)
    return failed_precondition("the training set's features are of pipeline version " +
                               std::to_string(set.feature_version) + ", this build computes version " +
                               std::to_string(kFeaturePipelineVersion) + ": train again from the clouds");
  order_by_object(set.samples);
  auto model = train_on_features(std::move(set.samples), with_learnt_density(set.clouds, params), progress, cancel, start);
  if (model.ok()) {
    count_given_clouds(*model, set.clouds);
    model->stats.seconds = ms_since(t0) / 1000.0;
  }
  return model;
}

Expected<Model> train(const std::vector<TrainingCloud>& data, const TrainParams& params, const ProgressFn& progress,
                      const CancelFn& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  auto set = training_set(data, params, progress, cancel);
  if (!set.ok()) return set.error();
  auto model = train(std::move(*set), params, progress, cancel);
  if (model.ok()) model->stats.seconds = ms_since(t0) / 1000.0;
  return model;
}

}  // namespace glimpse
