// run_evaluation: the paper's protocol (sec. 3.4, 4) end to end, phase by phase in the order the data
// flows: folds -> full 3D clouds -> single views -> features of every view and prefix (once, in
// parallel over clouds, one thread inside each) -> per fold: train from the stored features, classify
// its test clouds -> category changes -> streams -> what looks wrong. Results go to preallocated
// slots, so they do not depend on the thread count.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "glimpse/lab/evaluation.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/views/exploration.h"
#include "protocol.h"
#include "glimpse/threads.h"

namespace glimpse {

namespace {

using namespace eval_internal;

// --export-histograms: one row per cloud and method, the histogram the fold's model decides on
// (method_histogram): its training clouds (whole views, then their prefixes) and every tested stage.
// Objects are named as in decisions.csv.
Status export_histograms(const Protocol& P, int fold, const ModelImpl& impl, const std::vector<size_t>& test_views) {
  const std::filesystem::path path = std::filesystem::path(P.params.export_histograms_dir) / ("fold" + std::to_string(fold) + ".csv");
  std::ofstream o(path);
  if (!o) return invalid_argument("--export-histograms: cannot write " + path.string());
  o << "set,category,object,view,stage,keypoints,method,histogram...\n";
  auto rows = [&](const char* set, size_t v, const std::string& stage, const FeatureSlot& slot) {
    const size_t object = static_cast<size_t>(P.views[v].object);
    for (MethodId m : P.params.methods) {
      if (m == MethodId::kFusion || !impl.stages[static_cast<int>(m)]) continue;
      const Eigen::VectorXd h = method_histogram(impl, m, slot.features);
      o << set << ',' << P.objects[object].category << ',' << P.r.object_ids[object] << ',' << P.views[v].view << ','
        << stage << ',' << slot.features.positions.size() << ',' << method_name(m);
      for (Eigen::Index i = 0; i < h.size(); ++i) o << ',' << h[i];
      o << '\n';
    }
  };
  for (size_t v = 0; v < P.views.size(); ++v) {
    if (P.r.object_fold[static_cast<size_t>(P.views[v].object)] == fold || !P.learnt(v)) continue;
    for (size_t k = 0; k < P.train_slots[v].size(); ++k)
      if (const FeatureSlot& slot = P.slots[static_cast<size_t>(P.train_slots[v][k])]; slot.ok)
        rows(k == 0 ? "train" : "train-prefix", v, k == 0 ? "full" : "prefix", slot);
  }
  for (size_t v : test_views)
    for (size_t s = 0; s < P.stages.size(); ++s)
      if (const int id = P.stage_slot[v][s]; id >= 0 && P.slots[static_cast<size_t>(id)].ok)
        rows("test", v, stage_name(P.stages[s]), P.slots[static_cast<size_t>(id)]);
  o.flush();
  if (!o) return invalid_argument("--export-histograms: writing " + path.string() + " failed");
  return {};
}

// ---- 5. per fold: train on the other folds' (or the training sources') views, classify its test views ----

// The objects fold `fold`'s model may learn (EvalParams::objects_per_category): of each category's
// learnable objects outside the fold, the K first in the order of their seeds (the run's seed and the
// fold with the object's name); every one when K is 0.
std::vector<bool> few_shot_objects(const Protocol& P, int fold) {
  const size_t k = P.params.objects_per_category;
  std::vector<bool> learns(P.objects.size(), k == 0);
  if (k == 0) return learns;
  std::map<std::string, std::vector<std::pair<uint64_t, size_t>>> by_category;
  for (size_t o = 0; o < P.objects.size(); ++o)
    if (P.learnt_object(o) && P.r.object_fold[o] != fold)
      by_category[P.objects[o].category].push_back(
          {glimpse::object_seed(P.params.seed + uint64_t(fold + 1), P.objects[o].source + "/" + P.key(o)), o});
  for (auto& [category, objects] : by_category) {
    std::sort(objects.begin(), objects.end());
    for (size_t i = 0; i < std::min(k, objects.size()); ++i) learns[objects[i].second] = true;
  }
  return learns;
}

// The samples fold `fold`'s model learns from (each learnt view whole, then its prefixes, with the same
// clouds as seen when they differ), and into `test_views` the views it tests. Augmented
// (TrainingCloud::augmented: learnt, but not what novelty measures against): a simulated sensor's
// training views, and the procedural zoo's objects when added to real ones (--also-train zoo:N).
std::vector<TrainingSample> fold_samples(const Protocol& P, int fold, std::vector<size_t>& test_views) {
  std::vector<TrainingSample> samples;
  const std::vector<bool> learns = few_shot_objects(P, fold);
  for (size_t v = 0; v < P.views.size(); ++v) {
    const int o = P.views[v].object;
    if (P.r.object_fold[static_cast<size_t>(o)] == fold) {
      if (!P.views[v].train_only) test_views.push_back(v);
      continue;
    }
    if (!P.learnt(v) || !learns[static_cast<size_t>(o)]) continue;
    const EvalObject& object = P.objects[static_cast<size_t>(o)];
    const std::string id = object.source + "/" + object.category + "/" + object.id;  // the zoo's ids repeat per category
    for (size_t k = 0; k < P.train_slots[v].size(); ++k) {  // the whole (learnt) view, then its prefixes
      const FeatureSlot& slot = P.slots[static_cast<size_t>(P.train_slots[v][k])];
      if (!slot.ok) continue;
      const bool augmented = P.params.novelty_models && P.augmented(v);
      samples.push_back({object.category, id, slot.features, k == 0, std::nullopt, augmented});
      const FeatureSlot& seen = P.slots[static_cast<size_t>(P.seen_slots[v][k])];
      if (&seen != &slot && seen.ok) samples.back().as_seen = seen.features;
    }
  }
  return samples;
}

// What the report shows of a fold model's calibration.
void record_calibration(EvalResult& r, const ModelImpl& impl) {
  r.settle_margins.push_back(impl.calibration.settle_margin);
  r.calibration_accuracy.push_back(impl.calibration.held_out_accuracy);
  r.fusion_head_shares.push_back(impl.fusion_head ? impl.calibration.fusion_head_share : 0.0);
  r.probability_temperatures.push_back(impl.calibration.probability_temperature);
  r.settle_probabilities.push_back(impl.calibration.settle_probability);
  r.novelty_thresholds.push_back(novelty_calibration(impl).novelty_threshold);
  r.novelty_models += impl.novelty != nullptr;
}

// Fold `fold`'s test views decided by its model, every stage by every method, in preallocated slots
// (view, stage, method); `to_ours` maps the model's categories to the report's.
std::vector<StageDecision> classify_fold(const Protocol& P, int fold, const Model& model, const std::vector<int>& to_ours,
                                         const std::vector<size_t>& test_views, const std::string& tag) {
  const EvalResult& r = P.r;
  const size_t n_cat = r.categories.size();
  const ModelImpl& impl = *model.impl;
  const size_t n_methods = P.params.methods.size(), per_view = P.stages.size() * n_methods;
  std::vector<StageDecision> decisions(test_views.size() * per_view);
  parallel_for(test_views.size() * P.stages.size(), P.threads, tag + ": classify", P.progress, [&](size_t item) {
    const size_t t = item / P.stages.size(), s = item % P.stages.size();
    const size_t v = test_views[t];
    const int id = P.stage_slot[v][s];
    const bool ok = id >= 0 && P.slots[id].ok;
    for (size_t m = 0; m < n_methods; ++m) {
      StageDecision& d = decisions[t * per_view + s * n_methods + m];
      d.fold = fold;
      d.object = P.views[v].object;
      d.view = P.views[v].view;
      d.stage = stage_name(P.stages[s]);
      d.method = P.params.methods[m];
      d.truth = r.object_truth[static_cast<size_t>(d.object)];
      d.unknown_class = r.object_unknown_class[static_cast<size_t>(d.object)];
      d.points = id >= 0 ? P.slots[id].count : 0;
      d.visible_fraction = double(d.points) / double(P.full_points(v));
      if (!ok) continue;
      d.keypoints = P.slots[id].features.positions.size();
      const MethodDecision decision = method_decision(impl, d.method, P.slots[id].features);
      const Eigen::VectorXd& scores = decision.scores;
      d.scores.assign(n_cat, 0.0);
      for (int c = 0; c < static_cast<int>(scores.size()); ++c) d.scores[to_ours[c]] = scores[c];
      const std::vector<double> p = calibrated_probabilities(impl.calibration, d.method, {scores.data(), size_t(scores.size())});
      if (!p.empty()) d.probabilities.assign(n_cat, 0.0);
      for (size_t c = 0; c < p.size(); ++c) d.probabilities[size_t(to_ours[c])] = p[c];
      Classification c;
      c.method = d.method;
      c.winner = argmax(scores);
      judge_unknown(model, decision, P.slots[id].features, c);
      d.winner = to_ours[c.winner];
      d.novelty = c.novelty;
      d.unknown = c.unknown;
    }
  });
  return decisions;
}

Status train_and_classify(Protocol& P) {
  EvalResult& r = P.r;
  double train_seconds = 0, classify_seconds = 0;
  size_t train_samples = 0;
  for (int fold = 0; fold < P.folds; ++fold) {
    const std::string tag = r.cross_source ? std::string("all sources") : "fold " + std::to_string(fold + 1) + "/" + std::to_string(P.folds);
    auto t0 = Clock::now();
    if (P.progress) P.progress({tag + ": train", 0, 1});
    std::vector<size_t> test_views;
    std::vector<TrainingSample> samples = fold_samples(P, fold, test_views);
    train_samples += samples.size();
    TrainParams tp = P.tp;  // the model records the density its training views had (scan filters)
    tp.filters.relative_density = r.trained_density[size_t(fold)];
    auto trained = train_on_features(std::move(samples), tp);
    if (!trained.ok()) return Error{trained.error().code, tag + ": training failed: " + trained.error().message};
    const auto model = std::make_shared<const Model>(std::move(*trained));
    P.fold_models.push_back(model);
    record_calibration(r, *model->impl);
    train_seconds += seconds_since(t0);
    if (P.progress) P.progress({tag + ": train", 1, 1});

    if (!P.params.export_histograms_dir.empty())
      if (Status s = export_histograms(P, fold, *model->impl, test_views); !s.ok()) return s;
    t0 = Clock::now();
    std::vector<int> to_ours;
    for (const std::string& c : model->categories)
      to_ours.push_back(static_cast<int>(std::find(r.categories.begin(), r.categories.end(), c) - r.categories.begin()));
    P.fold_to_ours.push_back(to_ours);
    std::vector<StageDecision> decisions = classify_fold(P, fold, *model, to_ours, test_views, tag);
    r.decisions.insert(r.decisions.end(), std::make_move_iterator(decisions.begin()),
                       std::make_move_iterator(decisions.end()));
    classify_seconds += seconds_since(t0);
  }
  r.timings.push_back({r.cross_source ? "train" : "train (all folds)", train_seconds,
                       std::to_string(train_samples / static_cast<size_t>(P.folds)) + " samples per model"});
  r.timings.push_back({r.cross_source ? "classify" : "classify (all folds)", classify_seconds,
                       std::to_string(r.decisions.size()) + " decisions"});
  return {};
}

// ---- 6. category changes of the recogniser's default method (chosen before testing, not by the results) ----
void exploration_changes(Protocol& P) {
  EvalResult& r = P.r;
  r.change_method = P.tp.default_method;
  r.traces = exploration_traces(r.decisions, r.change_method, r.grid);
  r.changes = change_summary(r.traces, P.params.change_up_to);
}

// ---- 7. streaming: every tested view revealed top to bottom through a ScanSession of its fold's model ----
void stream_views(Protocol& P) {
  if (P.params.stream_chunk_fraction <= 0) return;
  EvalResult& r = P.r;
  const auto t0 = Clock::now();
  std::vector<size_t> tested;
  for (size_t v = 0; v < P.views.size(); ++v)
    if (P.tested(v)) tested.push_back(v);  // views of no learnt category too: does "unknown" settle?
  r.streams.resize(tested.size());
  SessionParams sp = P.params.session;
  sp.method = r.change_method;
  parallel_for(tested.size(), P.threads, "streaming sessions", P.progress, [&](size_t i) {
    const size_t v = tested[i];
    const int o = P.views[v].object, fold = r.object_fold[static_cast<size_t>(o)];
    StreamTrace& t = r.streams[i];
    t.fold = fold, t.object = o, t.view = P.views[v].view, t.truth = r.object_truth[static_cast<size_t>(o)];
    t.unknown_class = r.object_unknown_class[static_cast<size_t>(o)];
    auto session = ScanSession::create(P.fold_models[static_cast<size_t>(fold)], sp);
    if (!session.ok()) return;
    const Cloud& cloud = P.views[v].cloud;
    const std::vector<uint32_t> order = top_down_order(cloud.points);
    const size_t chunk =
        std::max<size_t>(1, static_cast<size_t>(std::lround(P.params.stream_chunk_fraction * double(P.full_points(v)))));
    Cloud part;
    part.sensor = cloud.sensor;
    part.frame = cloud.frame;
    for (size_t begin = 0; begin < order.size(); begin += chunk) {
      const size_t end = std::min(order.size(), begin + chunk);
      part.points.clear();
      for (size_t k = begin; k < end; ++k) part.points.push_back(cloud.points[order[k]]);
      auto d = (*session)->add(part);
      if (!d.ok()) break;
      t.visible_fraction.push_back(double(end) / double(P.full_points(v)));
      t.winners.push_back(d->winner >= 0 ? P.fold_to_ours[static_cast<size_t>(fold)][static_cast<size_t>(d->winner)] : -1);
      t.confidence.push_back(d->confidence);
      t.settled.push_back(d->settled ? 1 : 0);
      t.unknown.push_back(d->unknown ? 1 : 0);
      t.novelty.push_back(d->novelty);
      t.keypoints.push_back(d->keypoints);
      t.points.push_back(d->points);
      std::vector<double> raw(r.categories.size(), 0.0);
      for (size_t c = 0; c < d->raw_scores.size(); ++c)
        raw[static_cast<size_t>(P.fold_to_ours[static_cast<size_t>(fold)][c])] = d->raw_scores[c];
      t.raw_scores.push_back(std::move(raw));
    }
  });
  size_t chunks = 0;
  for (const StreamTrace& t : r.streams) chunks += t.winners.size();
  r.timings.push_back({"streaming sessions", seconds_since(t0),
                       std::to_string(r.streams.size()) + " views, " + std::to_string(chunks) + " chunks (" +
                           method_name(r.change_method) + ")"});
}

}  // namespace

Expected<EvalResult> run_evaluation(const std::vector<EvalObject>& objects, const EvalParams& params,
                                    std::string source, const EvalProgressFn& progress) {
  if (Status s = validate(objects, params); !s.ok()) return s.error();
  const auto t_start = Clock::now();
  Protocol P{objects, params, progress};
  P.r.params = params;
  P.r.source = std::move(source);
  P.threads = resolve_threads(params.threads);
  P.r.threads = P.threads;
  P.zoo_added = std::any_of(objects.begin(), objects.end(), [](const EvalObject& o) {
    return (o.role == EvalRole::kCrossValidate || o.role == EvalRole::kTrainOnly) && o.source != "zoo";
  });
  P.tp = params.train;
  P.tp.methods = params.methods;
  P.tp.seed = params.seed;
  P.tp.threads = P.threads;
  if (!contains(P.tp.methods, P.tp.default_method)) P.tp.default_method = P.tp.methods.front();
  P.base = base_methods(P.tp);
  P.features = method_feature_params(P.tp);
  P.recipe.points = params.points_per_object;
  P.recipe.views = std::clamp<size_t>(params.views_per_object, 1, 6);
  P.recipe.hpr_radius_factor = params.hpr_radius_factor;
  P.recipe.seed = params.seed;
  P.recipe.train_elevations_deg = params.train_elevations_deg;
  P.recipe.train_sensors = params.train_conditions;
  P.recipe.filters = params.filters;
  P.r.grid = exploration_grid(params.explore_max_keypoints, params.explore_step);
  P.stages = params.stages;
  for (size_t g : P.r.grid)
    if (const Stage s{StageKind::kKeypoints, double(g)}; std::find(P.stages.begin(), P.stages.end(), s) == P.stages.end())
      P.stages.push_back(s);

  assign_folds(P);
  make_object_clouds(P);
  make_views(P);
  trained_densities(P);
  sensor_training_views(P);
  sensor_test_views(P);
  full_view_features(P);
  prefix_features(P);
  stage_statistics(P);
  if (Status s = train_and_classify(P); !s.ok()) return s.error();
  exploration_changes(P);
  stream_views(P);
  robustness_matrix(P);
  flag_problems(P);
  P.r.total_seconds = seconds_since(t_start);
  return std::move(P.r);
}

}  // namespace glimpse
