// Training (sec. 3.2.5-3.3.3, 4): features of every training cloud -> keypoint codebooks -> per-method
// global histograms -> Bag-of-Features decision stages -> calibration on held-out folds.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "glimpse/learning/training.h"

#include "glimpse/clock.h"
#include "glimpse/learning/calibration.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/scores.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/threads.h"
#include "glimpse/views/exploration.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/sampling.h"

namespace glimpse {

// ---- Training -------------------------------------------------------------------------------------

const Calibration& calibration(const Model& model) {
  static const Calibration none;
  return model.impl ? model.impl->calibration : none;
}

const Calibration& novelty_calibration(const Model& model) {
  return model.impl ? novelty_calibration(*model.impl) : calibration(model);
}

std::vector<MethodId> base_methods(const TrainParams& params) {
  std::vector<MethodId> base;
  for (MethodId m : params.methods)
    if (m != MethodId::kFusion && !needs(base, m)) base.push_back(m);
  if (needs(params.methods, MethodId::kFusion))
    for (MethodId m : params.fusion_of)
      if (m != MethodId::kFusion && !needs(base, m)) base.push_back(m);
  return base;
}

Cloud training_view(const Cloud& cloud, const TrainParams& params, uint64_t salt) {
  if (!(params.tilt_deg > 0)) return cloud;
  uint64_t z = params.seed + 0x9E3779B97F4A7C15ull * (salt + 1);  // splitmix64 of (seed, salt)
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return rotate_about_centroid(cloud, random_tilt(z ^ (z >> 31), params.tilt_deg));
}

namespace {

template <class Sample>
Status validate(const std::vector<Sample>& data, const TrainParams& params) {
  if (data.empty()) return invalid_argument("no training clouds");
  if (params.methods.empty()) return invalid_argument("no method to train");
  for (size_t i = 0; i < data.size(); ++i)
    if (data[i].category.empty()) return invalid_argument("training cloud " + std::to_string(i) + " has no category");
  std::set<std::string> categories;
  for (const auto& d : data) categories.insert(d.category);
  if (categories.size() < 2)
    return failed_precondition("training needs at least 2 categories; got only '" + *categories.begin() + "'");
  if (Status s = check_codebook_sizes(params); !s.ok()) return s;
  if (!(params.known_acceptance > 0 && params.known_acceptance <= 1))
    return invalid_argument("known_acceptance must be in (0, 1]");
  if (!(params.novelty_prefix >= 0 && params.novelty_prefix <= 1))
    return invalid_argument("novelty_prefix must be in [0, 1] (0: no prefix)");
  return {};
}


// Every keypoint descriptor of the training set, subsampled evenly above `cap` rows.
Eigen::MatrixXd pooled_descriptors(const std::vector<CloudFeatures>& feats, size_t cap) {
  size_t total = 0;
  for (const auto& f : feats) total += f.descriptors.size();
  const size_t step = std::max<size_t>(1, (total + cap - 1) / cap);
  std::vector<Descriptor> rows;
  size_t i = 0;
  for (const auto& f : feats)
    for (const Descriptor& d : f.descriptors)
      if (i++ % step == 0) rows.push_back(d);
  return descriptor_rows(rows);
}

}  // namespace

Expected<Model> train(const std::vector<TrainingCloud>& data, const TrainParams& params, const ProgressFn& progress,
                      const CancelFn& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = validate(data, params); !s.ok()) return s.error();
  auto cancelled_now = [&] { return cancel && cancel(); };
  const std::vector<MethodId> base = base_methods(params);

  // The clouds to learn from: each training cloud whole, then its top-down prefixes (0 = whole).
  struct Job {
    size_t cloud;
    size_t prefix;
  };
  std::vector<Job> jobs;
  std::vector<Cloud> learnt(data.size());
  std::map<std::string, uint64_t> seen;  // clouds so far per object
  for (size_t i = 0; i < data.size(); ++i) {
    // The tilt is seeded by the object's name and the cloud's place among its views, not by its
    // place in the list: the same views learnt anywhere (the lab, the service) get the same tilts.
    const uint64_t salt = data[i].object_id.empty() ? i : object_seed(params.seed, data[i].object_id) + seen[data[i].object_id]++;
    learnt[i] = training_view(data[i].cloud, params, salt);
    jobs.push_back({i, 0});
    const size_t n = data[i].cloud.points.size();
    for (double f : params.partial_prefixes) {
      const auto count = static_cast<size_t>(std::lround(f * static_cast<double>(n)));
      if (count >= params.features.min_points && count < n) jobs.push_back({i, count});
    }
  }
  // Features of every job, in parallel; batches keep progress and cancel responsive.
  const int threads = resolve_threads(params.threads);
  std::vector<Expected<CloudFeatures>> feats(jobs.size(), internal_error("not computed"));
  // Tilted training views: the clouds as given are what calibration decides (what a sensor sends).
  const bool tilted = params.tilt_deg > 0 && params.calibration_folds >= 2;
  std::vector<Expected<CloudFeatures>> as_seen(tilted ? jobs.size() : 0, internal_error("not computed"));
  const MethodFeatureParams as_given = method_feature_params(params);
  MethodFeatureParams learnt_only = as_given;
  learnt_only.top_prefix_fraction = 0;
  const size_t batch = static_cast<size_t>(threads) * 4;
  for (size_t begin = 0; begin < jobs.size(); begin += batch) {
    if (cancelled_now()) return cancelled("training cancelled");
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
  std::vector<TrainingSample> samples;
  samples.reserve(jobs.size());
  for (size_t j = 0; j < jobs.size(); ++j) {
    const TrainingCloud& d = data[jobs[j].cloud];
    if (!feats[j].ok()) {
      // A whole cloud must work; a prefix too small or too thin for a method is only skipped.
      if (jobs[j].prefix && feats[j].error().code == ErrorCode::kInvalidArgument) continue;
      return Error{feats[j].error().code, "training cloud " + std::to_string(jobs[j].cloud) + " (category '" +
                                              d.category + "', object '" + d.object_id + "')" +
                                              (jobs[j].prefix ? ", top " + std::to_string(jobs[j].prefix) + " points" : "") +
                                              ": " + feats[j].error().message};
    }
    samples.push_back({d.category, d.object_id, std::move(*feats[j]), jobs[j].prefix == 0, std::nullopt, d.augmented});
    if (tilted && as_seen[j].ok()) samples.back().as_seen = std::move(*as_seen[j]);
  }
  feats.clear();
  as_seen.clear();
  // The density clouds are classified at: the median relative density of the training clouds as given.
  TrainParams learnt_params = params;
  if (params.filter_scans && params.filters.relative_density <= 0) {
    std::vector<double> density(data.size(), 0.0);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int64_t i = 0; i < static_cast<int64_t>(data.size()); ++i) density[i] = relative_density(data[i].cloud.points);
    std::erase(density, 0.0);
    if (!density.empty()) {
      std::nth_element(density.begin(), density.begin() + std::ptrdiff_t(density.size() / 2), density.end());
      learnt_params.filters.relative_density = density[density.size() / 2];
    }
  }
  auto model = train_on_features(std::move(samples), learnt_params, progress, cancel);
  if (model.ok()) {
    // Statistics count the clouds given, not the prefixes made of them.
    model->stats.clouds = data.size();
    std::fill(model->stats.clouds_per_category.begin(), model->stats.clouds_per_category.end(), 0);
    for (const TrainingCloud& d : data)
      ++model->stats.clouds_per_category[static_cast<size_t>(
          std::find(model->categories.begin(), model->categories.end(), d.category) - model->categories.begin())];
    model->stats.seconds = ms_since(t0) / 1000.0;
  }
  return model;
}

Expected<Model> train_on_features(std::vector<TrainingSample> data, const TrainParams& params,
                                  const ProgressFn& progress, const CancelFn& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = validate(data, params); !s.ok()) return s.error();
  auto report = [&](const char* stage, size_t done, size_t total) {
    if (progress) progress({stage, done, total});
  };
  auto cancelled_now = [&] { return cancel && cancel(); };

  Model model;
  auto impl = std::make_shared<ModelImpl>();
  impl->params = params;
  std::map<std::string, int> index;
  for (const auto& d : data) index.emplace(d.category, 0);
  for (auto& [name, i] : index) {
    i = static_cast<int>(model.categories.size());
    model.categories.push_back(name);
  }
  CalibrationRows rows;  // what calibration decides again, held out (step 4)
  std::vector<int>& labels = rows.labels;
  std::vector<int>& object_of = rows.objects;
  std::vector<uint8_t>& whole = rows.whole;
  std::map<std::string, int> object_index;
  for (const auto& d : data) {
    labels.push_back(index[d.category]);
    whole.push_back(d.whole ? 1 : 0);
    // A cloud without an object id is an object of its own.
    const std::string key = d.object_id.empty() ? "#" + std::to_string(labels.size()) : d.category + "/" + d.object_id;
    object_of.push_back(object_index.emplace(key, static_cast<int>(object_index.size())).first->second);
  }

  // What novelty measures against when some clouds were augmented: the others, learnt apart (step 5).
  const size_t augmented = static_cast<size_t>(std::count_if(data.begin(), data.end(), [](const TrainingSample& d) { return d.augmented; }));
  const bool novelty_apart = augmented > 0 && augmented < data.size();

  const std::vector<MethodId> base = base_methods(params);
  const int threads = resolve_threads(params.threads);
  std::vector<CloudFeatures> f;
  std::vector<std::optional<CloudFeatures>> as_seen;
  f.reserve(data.size());
  for (auto& d : data) f.push_back(std::move(d.features)), as_seen.push_back(std::move(d.as_seen));

  // 2. Keypoint codebooks (sec. 3.2.5).
  report("codebooks", 0, 3);
  const Eigen::MatrixXd pooled = std::any_of(base.begin(), base.end(), uses_keypoints)
                                     ? pooled_descriptors(f, 100000) : Eigen::MatrixXd();
  auto codebook = [&](int clusters, uint64_t salt) {
    return fit_keypoint_codebook(pooled, {clusters, params.codebook_explained_variance, params.kmeans_restarts,
                                          params.seed + salt, threads});
  };
  auto with_method = [&](MethodId m, const Error& e) {
    return Error{e.code, std::string(method_name(m)) + ": " + e.message};
  };
  if (needs(base, MethodId::kBoK)) {
    auto cb = codebook(params.bok_clusters, 1);
    if (!cb.ok()) return with_method(MethodId::kBoK, cb.error());
    impl->bok = std::move(*cb);
  }
  if (needs(base, MethodId::kBoG)) {
    auto cb = codebook(params.bog_keypoint_clusters, 2);
    if (!cb.ok()) return with_method(MethodId::kBoG, cb.error());
    impl->bog = std::move(*cb);
    std::vector<std::vector<LocalGraph>> graphs;
    for (const auto& c : f) graphs.push_back(local_graphs(c.positions, keypoint_words(impl->bog, c.descriptors)));
    auto voc = fit_graph_vocabulary(graphs, params.bog_keypoint_clusters, params.bog_volume_clusters, params.seed + 3);
    if (!voc.ok()) return with_method(MethodId::kBoG, voc.error());
    impl->graphs = std::move(*voc);
  }
  if (needs(base, MethodId::kKGH)) {
    auto cb = codebook(params.kgh_clusters, 4);
    if (!cb.ok()) return with_method(MethodId::kKGH, cb.error());
    impl->kgh = std::move(*cb);
    // Distance bins span the largest keypoint distance seen in training (robustly: its 95th percentile).
    std::vector<float> spans;
    for (const auto& c : f) {
      float span = 0;
      for (size_t i = 0; i < c.positions.size(); ++i)
        for (size_t j = i + 1; j < c.positions.size(); ++j) span = std::max(span, (c.positions[i] - c.positions[j]).norm());
      if (span > 0) spans.push_back(span);
    }
    std::sort(spans.begin(), spans.end());
    impl->kgh_max_distance_m = spans.empty() ? 1.f : spans[std::min(spans.size() - 1, spans.size() * 95 / 100)];
  }
  report("codebooks", 3, 3);
  if (cancelled_now()) return cancelled("training cancelled");

  // 3. Global histograms and decision stages (sec. 3.3).
  size_t done = 0;
  const bool tilted = std::any_of(as_seen.begin(), as_seen.end(), [](const auto& a) { return a.has_value(); });
  std::vector<Eigen::MatrixXd>& histograms = rows.histograms;
  std::vector<Eigen::MatrixXd>& queries = rows.as_seen;
  std::vector<Eigen::MatrixXd>& prefix_queries = rows.prefix_histograms;
  histograms.resize(kMethodCount);
  prefix_queries.resize(kMethodCount);
  queries.resize(kMethodCount);  // emptied below when nothing is tilted: the rows as learnt
  // The top-down prefix of each row as calibration decides it (of the cloud as given when tilted).
  std::vector<const CloudFeatures*> prefix_of(f.size(), nullptr);
  std::vector<uint8_t>& has_prefix = rows.has_prefix;
  has_prefix.assign(f.size(), 0);
  for (size_t i = 0; i < f.size(); ++i) {
    const CloudFeatures& seen = tilted && as_seen[i] ? *as_seen[i] : f[i];
    prefix_of[i] = seen.top_prefix.get();
    has_prefix[i] = prefix_of[i] != nullptr;
  }
  const bool any_prefix = std::count(has_prefix.begin(), has_prefix.end(), 1) > 0;
  for (MethodId m : base) {
    Eigen::MatrixXd& h = histograms[static_cast<size_t>(m)];
    Eigen::MatrixXd& q = queries[static_cast<size_t>(m)];
    Eigen::MatrixXd& pq = prefix_queries[static_cast<size_t>(m)];
    for (size_t i = 0; i < f.size(); ++i) {
      const Eigen::VectorXd row = method_histogram(*impl, m, f[i]);
      if (i == 0) h.resize(static_cast<Eigen::Index>(f.size()), row.size());
      if (i == 0 && any_prefix) pq.setZero(static_cast<Eigen::Index>(f.size()), row.size());
      h.row(static_cast<Eigen::Index>(i)) = row.transpose();
      if (prefix_of[i]) pq.row(static_cast<Eigen::Index>(i)) = method_histogram(*impl, m, *prefix_of[i]).transpose();
      if (!tilted) continue;
      if (i == 0) q.resize(h.rows(), h.cols());
      if (as_seen[i]) q.row(static_cast<Eigen::Index>(i)) = method_histogram(*impl, m, *as_seen[i]).transpose();
      else q.row(static_cast<Eigen::Index>(i)) = h.row(static_cast<Eigen::Index>(i));
    }
    DecisionParams dp = params.decision;
    if (m == MethodId::kBoG) {  // 1032 graph types reduced to 65 dims (sec. 4), also without PCA elsewhere
      dp.max_pca_dims = params.bog_pca_dims;
      if (dp.pca_explained_variance <= 0) dp.pca_explained_variance = 1;
    }
    auto stage = fit_decision(h, labels, static_cast<int>(model.categories.size()), dp,
                              params.seed + 10 + static_cast<uint64_t>(m), threads, object_of);
    if (!stage.ok()) return with_method(m, stage.error());
    impl->stages[static_cast<int>(m)] = std::move(*stage);
    report("centres", ++done, base.size());
    if (cancelled_now()) return cancelled("training cancelled");
  }

  if (!tilted) queries.clear();
  for (MethodId m : kAllMethods)
    if (needs(params.methods, m)) model.methods.push_back(m);
  if (needs(model.methods, MethodId::kFusion) && component_methods(*impl, MethodId::kFusion).empty())
    return invalid_argument("fusion needs at least one of its component methods (fusion_of)");
  model.default_method = needs(model.methods, params.default_method) ? params.default_method : model.methods.front();
  // 3b. The fusion's logistic decision over its components' histograms (its share is calibrated below).
  if (cancelled_now()) return cancelled("training cancelled");
  if (needs(model.methods, MethodId::kFusion) && params.fusion_head.c > 0 && model.categories.size() >= 2 &&
      !fusion_head_methods(*impl).empty()) {
    auto head = fit_chi2_logistic(fusion_head_rows(*impl, histograms, {}, threads), labels, static_cast<int>(model.categories.size()),
                                  params.fusion_head, threads);
    if (!head.ok()) return with_method(MethodId::kFusion, head.error());
    impl->fusion_head = std::move(*head);
  }
  // 4. Calibration of the default method on held-out folds of the training objects.
  report("calibration", 0, 1);
  rows.object_categories.resize(object_index.size());
  for (size_t i = 0; i < labels.size(); ++i)
    rows.object_categories[static_cast<size_t>(object_of[i])] = model.categories[static_cast<size_t>(labels[i])];
  rows.categories = static_cast<int>(model.categories.size());
  // Nothing learnt tilted: the held-out clouds are decided as they were learnt. With augmented clouds
  // the novelty model's calibration measures novelty (step 5); this one does only if that fails.
  auto calibrate_model = [&](bool measure_novelty) {
    return calibrate(*impl, model.default_method, rows, measure_novelty, threads, cancel);
  };
  impl->calibration = calibrate_model(params.measure_novelty && !novelty_apart);
  report("calibration", 1, 1);
  if (cancelled_now()) return cancelled("training cancelled");
  model.stats.clouds = data.size();
  std::set<std::string> objects;
  for (const auto& d : data) objects.insert(d.category + "/" + d.object_id);
  model.stats.objects = objects.size();
  for (const auto& c : f) model.stats.keypoints += c.positions.size();
  model.stats.min_extent_m = INFINITY;
  for (const auto& c : f) {
    model.stats.min_extent_m = std::min(model.stats.min_extent_m, c.extent_m);
    model.stats.max_extent_m = std::max(model.stats.max_extent_m, c.extent_m);
  }
  model.stats.categories = model.categories;
  model.stats.clouds_per_category.assign(model.categories.size(), 0);
  for (int l : labels) ++model.stats.clouds_per_category[static_cast<size_t>(l)];

  // 5. Novelty from the clouds given as they are: the augmented ones widen the decision, not what is
  // known. Without a calibrated novelty there (too few objects of a category, or a category only
  // augmented clouds have), novelty stays the model's own. Their features move there (the stats
  // above were the last to read them), so they are never held twice.
  if (novelty_apart) {
    std::vector<TrainingSample> given;
    for (size_t i = 0; i < data.size(); ++i)
      if (!data[i].augmented)
        given.push_back({std::move(data[i].category), std::move(data[i].object_id), std::move(f[i]), data[i].whole,
                         std::move(as_seen[i]), false});
    report("novelty", 0, 1);
    auto novelty = train_on_features(std::move(given), params, {}, cancel);
    if (cancelled_now()) return cancelled("training cancelled");
    if (novelty.ok() && novelty->categories == model.categories && novelty->impl &&
        !novelty->impl->calibration.novelty_scale.empty() && novelty->impl->calibration.method == impl->calibration.method)
      impl->novelty = novelty->impl;
    else if (params.measure_novelty)
      impl->calibration = calibrate_model(true);  // the same margin and share, with the model's own novelty
    if (cancelled_now()) return cancelled("training cancelled");
    report("novelty", 1, 1);
  }
  model.stats.seconds = ms_since(t0) / 1000.0;
  model.impl = std::move(impl);
  report("done", 1, 1);
  return model;
}


}  // namespace glimpse
