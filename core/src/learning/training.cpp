// Training from computed features (sec. 3.2.5-3.3.3, 4), stage by stage: the rows' categories and
// objects -> keypoint codebooks -> per-method global histograms and decision stages -> the fusion's
// logistic decision -> calibration on held-out folds -> the novelty model of the clouds not augmented.
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
#include "glimpse/random.h"
#include "glimpse/threads.h"
#include "learning/training_checks.h"

namespace glimpse {

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

namespace {

// Training's progress and cancel, as its stages report and poll them.
struct Steps {
  const ProgressFn& progress;
  const CancelFn& cancel;
  void report(const char* stage, size_t done, size_t total) const {
    if (progress) progress({stage, done, total});
  }
  bool cancelled_now() const { return cancel && cancel(); }
};

Error with_method(MethodId m, const Error& e) { return Error{e.code, std::string(method_name(m)) + ": " + e.message}; }

// 1. The model's categories (sorted by name, into `categories`) and every row's category, object and
// wholeness: the rows calibration decides again, held out.
CalibrationRows labelled_rows(const std::vector<TrainingSample>& data, std::vector<std::string>& categories) {
  std::map<std::string, int> index;
  for (const auto& d : data) index.emplace(d.category, 0);
  for (auto& [name, i] : index) {
    i = static_cast<int>(categories.size());
    categories.push_back(name);
  }
  CalibrationRows rows;
  std::map<std::string, int> object_index;
  std::vector<uint64_t> object_rows;  // per object: its rows so far
  for (const auto& d : data) {
    rows.labels.push_back(index[d.category]);
    rows.whole.push_back(d.whole ? 1 : 0);
    // A cloud without an object id is an object of its own.
    const std::string key = d.object_id.empty() ? '#' + std::to_string(rows.labels.size()) : d.category + "/" + d.object_id;
    const auto [at, fresh] = object_index.emplace(key, static_cast<int>(object_index.size()));
    rows.objects.push_back(at->second);
    if (fresh) object_rows.push_back(0);
    rows.keys.push_back(splitmix64(name_hash(key), object_rows[static_cast<size_t>(at->second)]++));
  }
  rows.object_categories.resize(object_index.size());
  for (size_t i = 0; i < rows.labels.size(); ++i)
    rows.object_categories[static_cast<size_t>(rows.objects[i])] = categories[static_cast<size_t>(rows.labels[i])];
  rows.categories = static_cast<int>(categories.size());
  return rows;
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

// KGH's distance bins span the largest keypoint distance seen in training (robustly: its 95th percentile
// over the clouds).
float kgh_distance_range(const std::vector<CloudFeatures>& f) {
  std::vector<float> spans;
  for (const auto& c : f) {
    float span = 0;
    for (size_t i = 0; i < c.positions.size(); ++i)
      for (size_t j = i + 1; j < c.positions.size(); ++j) span = std::max(span, (c.positions[i] - c.positions[j]).norm());
    if (span > 0) spans.push_back(span);
  }
  std::sort(spans.begin(), spans.end());
  return spans.empty() ? 1.f : spans[std::min(spans.size() - 1, spans.size() * 95 / 100)];
}

// 2. Keypoint codebooks (sec. 3.2.5) of the methods that need them: BoK's, BoG's with its graph
// vocabulary, KGH's with its distance range.
Status fit_codebooks(ModelImpl& impl, const std::vector<CloudFeatures>& f, const std::vector<MethodId>& base,
                     const TrainParams& params, int threads) {
  const Eigen::MatrixXd pooled = std::any_of(base.begin(), base.end(), uses_keypoints)
                                     ? pooled_descriptors(f, 100000) : Eigen::MatrixXd();
  auto codebook = [&](int clusters, uint64_t salt) {
    return fit_keypoint_codebook(pooled, {clusters, params.codebook_explained_variance, params.kmeans_restarts,
                                          params.seed + salt, threads});
  };
  if (needs(base, MethodId::kBoK)) {
    auto cb = codebook(params.bok_clusters, 1);
    if (!cb.ok()) return with_method(MethodId::kBoK, cb.error());
    impl.bok = std::move(*cb);
  }
  if (needs(base, MethodId::kBoG)) {
    auto cb = codebook(params.bog_keypoint_clusters, 2);
    if (!cb.ok()) return with_method(MethodId::kBoG, cb.error());
    impl.bog = std::move(*cb);
    std::vector<std::vector<LocalGraph>> graphs;
    for (const auto& c : f) graphs.push_back(local_graphs(c.positions, keypoint_words(impl.bog, c.descriptors)));
    auto voc = fit_graph_vocabulary(graphs, params.bog_keypoint_clusters, params.bog_volume_clusters, params.seed + 3);
    if (!voc.ok()) return with_method(MethodId::kBoG, voc.error());
    impl.graphs = std::move(*voc);
  }
  if (needs(base, MethodId::kKGH)) {
    auto cb = codebook(params.kgh_clusters, 4);
    if (!cb.ok()) return with_method(MethodId::kKGH, cb.error());
    impl.kgh = std::move(*cb);
    impl.kgh_max_distance_m = kgh_distance_range(f);
  }
  return {};
}

// The features each row's calibration query comes from, as the decision stages take them: the rows as
// learnt, the same clouds as a sensor gives them (when tilted), and each row's own top-down prefix (of the
// cloud as given when tilted; null: none).
struct RowFeatures {
  const std::vector<CloudFeatures>& learnt;
  const std::vector<std::optional<CloudFeatures>>& as_seen;
  bool tilted = false;
  std::vector<const CloudFeatures*> prefix{};
  bool any_prefix = false;
};

// Method m's histogram of every row into `rows` (as learnt, as seen when tilted, of its prefix).
void method_rows(const ModelImpl& impl, MethodId m, const RowFeatures& f, CalibrationRows& rows) {
  Eigen::MatrixXd& h = rows.histograms[static_cast<size_t>(m)];
  Eigen::MatrixXd& q = rows.as_seen[static_cast<size_t>(m)];
  Eigen::MatrixXd& pq = rows.prefix_histograms[static_cast<size_t>(m)];
  const size_t n = f.learnt.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::VectorXd row = method_histogram(impl, m, f.learnt[i]);
    if (i == 0) h.resize(static_cast<Eigen::Index>(n), row.size());
    if (i == 0 && f.any_prefix) pq.setZero(static_cast<Eigen::Index>(n), row.size());
    h.row(static_cast<Eigen::Index>(i)) = row.transpose();
    if (f.prefix[i]) pq.row(static_cast<Eigen::Index>(i)) = method_histogram(impl, m, *f.prefix[i]).transpose();
    if (!f.tilted) continue;
    if (i == 0) q.resize(h.rows(), h.cols());
    if (f.as_seen[i]) q.row(static_cast<Eigen::Index>(i)) = method_histogram(impl, m, *f.as_seen[i]).transpose();
    else q.row(static_cast<Eigen::Index>(i)) = h.row(static_cast<Eigen::Index>(i));
  }
}

// The decision parameters of the model's own stage of method m: BoG's 1032 graph types reduced to 65 dims
// (sec. 4), by PCA even where the other methods have none.
DecisionParams model_stage_params(const TrainParams& params, MethodId m) {
  DecisionParams dp = params.decision;
  if (m == MethodId::kBoG) {
    dp.max_pca_dims = params.bog_pca_dims;
    if (dp.pca_explained_variance <= 0) dp.pca_explained_variance = 1;
  }
  return dp;
}

// 3. Global histograms and decision stages (sec. 3.3), method by method.
// Progress: "centres", one step per method and one for the fusion's logistic decision after them.
Status fit_decision_stages(ModelImpl& impl, CalibrationRows& rows, const std::vector<CloudFeatures>& f,
                           const std::vector<std::optional<CloudFeatures>>& as_seen, const std::vector<MethodId>& base,
                           int threads, const Steps& steps) {
  RowFeatures features{f, as_seen};
  features.tilted = std::any_of(as_seen.begin(), as_seen.end(), [](const auto& a) { return a.has_value(); });
  rows.histograms.resize(kMethodCount);
  rows.prefix_histograms.resize(kMethodCount);
  rows.as_seen.resize(kMethodCount);  // emptied below when nothing is tilted: the rows as learnt
  features.prefix.assign(f.size(), nullptr);
  rows.has_prefix.assign(f.size(), 0);
  for (size_t i = 0; i < f.size(); ++i) {
    const CloudFeatures& seen = features.tilted && as_seen[i] ? *as_seen[i] : f[i];
    features.prefix[i] = seen.top_prefix.get();
    rows.has_prefix[i] = features.prefix[i] != nullptr;
  }
  features.any_prefix = std::count(rows.has_prefix.begin(), rows.has_prefix.end(), 1) > 0;
  size_t done = 0;
  for (MethodId m : base) {
    method_rows(impl, m, features, rows);
    auto stage = fit_decision(rows.histograms[static_cast<size_t>(m)], rows.labels, rows.categories,
                              model_stage_params(impl.params, m), impl.params.seed + 10 + static_cast<uint64_t>(m),
                              threads, rows.objects);
    if (!stage.ok()) return with_method(m, stage.error());
    impl.stages[static_cast<int>(m)] = std::move(*stage);
    steps.report("centres", ++done, base.size() + 1);
    if (steps.cancelled_now()) return cancelled("training cancelled");
  }
  if (!features.tilted) rows.as_seen.clear();
  return {};
}

// The methods the model classifies with (params.methods, in MethodId order) and its default.
Status choose_methods(Model& model, const ModelImpl& impl, const TrainParams& params) {
  for (MethodId m : kAllMethods)
    if (needs(params.methods, m)) model.methods.push_back(m);
  if (needs(model.methods, MethodId::kFusion) && component_methods(impl, MethodId::kFusion).empty())
    return invalid_argument("fusion needs at least one of its component methods (fusion_of)");
  model.default_method = needs(model.methods, params.default_method) ? params.default_method : model.methods.front();
  return {};
}

// Each of `folds` (heads over `from` categories) with its rows for `to`, a category `from` lacks at `others`'
// row (head_for_categories).
std::vector<Chi2Logistic> folds_for_categories(const std::vector<Chi2Logistic>& folds, const std::vector<std::string>& from,
                                               const std::vector<std::string>& to, const Chi2Logistic& others) {
  std::vector<Chi2Logistic> out;
  for (const Chi2Logistic& fold : folds) out.push_back(head_for_categories(fold, from, to, &others));
  return out;
}

// Whether `start` has a logistic decision over `features` mapped features to start from.
bool can_start_from(const Model* start, Eigen::Index features) {
  return start && start->impl && start->impl->fusion_head && start->impl->fusion_head->weights.cols() == features;
}

// 3b. The fusion's logistic decision over its components' histograms (its share is calibrated in step 4).
Status fit_fusion_head(ModelImpl& impl, const Model& model, const CalibrationRows& rows, int threads,
                       const Model* start) {
  const TrainParams& params = impl.params;
  if (!(needs(model.methods, MethodId::kFusion) && params.fusion_head.c > 0 && model.categories.size() >= 2 &&
        !fusion_head_methods(impl).empty()))
    return {};
  std::vector<Eigen::Index> learnt;  // empty: every row
  std::vector<int> labels = rows.labels;
  if (!rows.head_learns.empty()) {
    labels.clear();
    for (size_t i = 0; i < rows.labels.size(); ++i)
      if (rows.head_learns[i]) learnt.push_back(static_cast<Eigen::Index>(i)), labels.push_back(rows.labels[i]);
  }
  const Eigen::MatrixXd x = fusion_head_rows(impl, rows.histograms, learnt, threads);
  const bool started = can_start_from(start, x.cols());
  std::optional<Chi2Logistic> from;
  if (started) from = head_for_categories(*start->impl->fusion_head, start->categories, model.categories);
  auto head = fit_chi2_logistic(x, labels, static_cast<int>(model.categories.size()), params.fusion_head, threads,
                                from ? &*from : nullptr);
  if (!head.ok()) return with_method(MethodId::kFusion, head.error());
  impl.fusion_head = std::move(*head);
  // Each calibration fold starts at the start's same fold, a category it lacks at the head just learnt;
  // calibration keeps what the folds learn.
  impl.fold_heads.clear();
  if (started)
    impl.fold_heads = folds_for_categories(start->impl->fold_heads, start->categories, model.categories, *impl.fusion_head);
  return {};
}

// What the model says of its training set: clouds, objects, keypoints, extents, clouds per category.
TrainingSummary training_summary(const std::vector<TrainingSample>& data, const std::vector<CloudFeatures>& f,
                                 const std::vector<int>& labels, const std::vector<std::string>& categories) {
  TrainingSummary stats;
  stats.clouds = data.size();
  std::set<std::string> objects;
  for (const auto& d : data) objects.insert(d.category + "/" + d.object_id);
  stats.objects = objects.size();
  for (const auto& c : f) stats.keypoints += c.positions.size();
  stats.min_extent_m = INFINITY;
  for (const auto& c : f) {
    stats.min_extent_m = std::min(stats.min_extent_m, c.extent_m);
    stats.max_extent_m = std::max(stats.max_extent_m, c.extent_m);
  }
  stats.categories = categories;
  stats.clouds_per_category.assign(categories.size(), 0);
  for (int l : labels) ++stats.clouds_per_category[static_cast<size_t>(l)];
  return stats;
}

// 5. Novelty from the clouds given as they are: the augmented ones widen the decision, not what is
// known. The clouds not augmented train a model of their own (ModelImpl::novelty); without a calibrated
// novelty there (too few objects of a category, or a category only augmented clouds have), novelty stays
// the model's own, calibrated again with it. Their features move there (nothing reads them after), so
// they are never held twice.
Status learn_novelty_apart(ModelImpl& impl, const Model& model, const CalibrationRows& rows,
                           std::vector<TrainingSample>& data, std::vector<CloudFeatures>& f,
                           std::vector<std::optional<CloudFeatures>>& as_seen, int threads, const Steps& steps,
                           const Model* start) {
  const TrainParams& params = impl.params;
  std::vector<TrainingSample> given;
  for (size_t i = 0; i < data.size(); ++i)
    if (!data[i].augmented)
      given.push_back({std::move(data[i].category), std::move(data[i].object_id), std::move(f[i]), data[i].whole,
                       std::move(as_seen[i]), false});
  steps.report("novelty", 0, 1);
  // The novelty model starts at the start's novelty model, a category that lacks at this model's head.
  Model novelty_start;
  if (start && start->impl && start->impl->novelty && start->impl->novelty->fusion_head && impl.fusion_head) {
    const ModelImpl& base = *start->impl->novelty;
    auto from = std::make_shared<ModelImpl>();
    from->fusion_head = head_for_categories(*base.fusion_head, start->categories, model.categories, &*impl.fusion_head);
    from->fold_heads = folds_for_categories(base.fold_heads, start->categories, model.categories, *impl.fusion_head);
    novelty_start.categories = model.categories;
    novelty_start.impl = std::move(from);
  }
  auto novelty = train_on_features(std::move(given), params, {}, steps.cancel, novelty_start.impl ? &novelty_start : nullptr);
  if (steps.cancelled_now()) return cancelled("training cancelled");
  if (novelty.ok() && novelty->categories == model.categories && novelty->impl &&
      !novelty->impl->calibration.novelty_scale.empty() && novelty->impl->calibration.method == impl.calibration.method)
    impl.novelty = novelty->impl;
  else if (params.measure_novelty)  // the same margin and share, with the model's own novelty
    impl.calibration = calibrate(impl, model.default_method, rows, true, threads, steps.cancel);
  if (steps.cancelled_now()) return cancelled("training cancelled");
  steps.report("novelty", 1, 1);
  return {};
}

}  // namespace

Expected<Model> train_on_features(std::vector<TrainingSample> data, const TrainParams& params,
                                  const ProgressFn& progress, const CancelFn& cancel, const Model* start) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = check_training_set(data, params); !s.ok()) return s.error();
  const Steps steps{progress, cancel};
  Model model;
  auto impl = std::make_shared<ModelImpl>();
  impl->params = params;
  CalibrationRows rows = labelled_rows(data, model.categories);
  if (params.fusion_head_rows_per_category > 0)
    rows.head_learns = fusion_head_learns(rows.labels, rows.keys, rows.categories, params.fusion_head_rows_per_category,
                                          params.seed + 107);
  // With some clouds augmented, novelty measures against the others, learnt apart (step 5).
  const size_t augmented = static_cast<size_t>(std::count_if(data.begin(), data.end(), [](const TrainingSample& d) { return d.augmented; }));
  const bool novelty_apart = augmented > 0 && augmented < data.size();
  const std::vector<MethodId> base = base_methods(params);
  const int threads = resolve_threads(params.threads);
  std::vector<CloudFeatures> f;
  std::vector<std::optional<CloudFeatures>> as_seen;
  f.reserve(data.size());
  for (auto& d : data) f.push_back(std::move(d.features)), as_seen.push_back(std::move(d.as_seen));

  steps.report("codebooks", 0, 3);
  if (Status s = fit_codebooks(*impl, f, base, params, threads); !s.ok()) return s.error();
  steps.report("codebooks", 3, 3);
  if (steps.cancelled_now()) return cancelled("training cancelled");
  if (Status s = fit_decision_stages(*impl, rows, f, as_seen, base, threads, steps); !s.ok()) return s.error();
  if (Status s = choose_methods(model, *impl, params); !s.ok()) return s.error();
  if (steps.cancelled_now()) return cancelled("training cancelled");
  if (Status s = fit_fusion_head(*impl, model, rows, threads, start); !s.ok()) return s.error();
  steps.report("centres", base.size() + 1, base.size() + 1);
  // 4. Calibration of the default method on held-out folds of the training objects. With augmented
  // clouds the novelty model's calibration measures novelty (step 5); this one does only if that fails.
  const size_t folds = static_cast<size_t>(std::max(1, params.calibration_folds));
  steps.report("calibration", 0, folds);
  std::vector<Chi2Logistic> fold_heads = std::move(impl->fold_heads);
  impl->calibration = calibrate(*impl, model.default_method, rows, params.measure_novelty && !novelty_apart, threads,
                                cancel, [&](size_t k, size_t n) { steps.report("calibration", k, n); }, &fold_heads);
  impl->fold_heads = std::move(fold_heads);
  if (params.calibration_folds < 2) steps.report("calibration", folds, folds);  // else the last fold said so
  if (steps.cancelled_now()) return cancelled("training cancelled");
  model.stats = training_summary(data, f, rows.labels, model.categories);
  if (novelty_apart)
    if (Status s = learn_novelty_apart(*impl, model, rows, data, f, as_seen, threads, steps, start); !s.ok())
      return s.error();
  model.stats.seconds = ms_since(t0) / 1000.0;
  model.impl = std::move(impl);
  steps.report("done", 1, 1);
  return model;
}

}  // namespace glimpse
