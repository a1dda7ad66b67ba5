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
#include <map>
#include <set>

#include "glimpse/evaluation.h"
#include "glimpse/neighbourhoods.h"
#include "glimpse/surface_fit.h"
#include "glimpse/views.h"
#include "evaluation_internal.h"
#include "parallel.h"

namespace glimpse {

namespace {

using namespace eval_internal;

Status validate(const std::vector<EvalObject>& objects, const EvalParams& p) {
  if (objects.empty()) return invalid_argument("no objects to evaluate");
  if (p.methods.empty()) return invalid_argument("no method to evaluate");
  if (p.stages.empty()) return invalid_argument("no stage to evaluate");
  std::set<std::string> categories, learnt;
  size_t cv = 0, train = 0, test = 0;
  for (const EvalObject& o : objects) {
    if (o.mesh.vertices.empty()) return invalid_argument("object " + o.category + "/" + o.id + " has no vertices");
    categories.insert(o.category);
    if (o.role == EvalRole::kCrossValidate || o.role == EvalRole::kTrainOnly) learnt.insert(o.category);
    cv += o.role == EvalRole::kCrossValidate, train += o.role == EvalRole::kTrainOnly, test += o.role == EvalRole::kTestOnly;
  }
  for (const EvalObject& o : objects)
    if (o.role == EvalRole::kUnknown && learnt.count(o.category))
      return invalid_argument("'" + o.category + "' is learnt, so its objects cannot stand for the unknown");
  if (cv && test) return invalid_argument("objects are either cross-validated or split into training and test sources");
  if (cv) {
    if (p.folds < 2) return invalid_argument("cross-validation needs at least 2 folds");
    if (static_cast<size_t>(p.folds) > objects.size()) return invalid_argument("more folds than objects");
  } else if (!train || !test) {
    return invalid_argument("a cross-source evaluation needs training and test objects");
  }
  if (learnt.size() < 2) return invalid_argument("evaluation needs at least 2 categories to learn");
  for (const Stage& s : p.stages)
    if ((s.kind == StageKind::kKeypoints && !(s.value >= 1)) ||
        (s.kind == StageKind::kFraction && !(s.value > 0 && s.value <= 1)))
      return invalid_argument("bad stage " + stage_name(s));
  return {};
}

// ---- 0. categories, folds, sources ----
void assign_folds(Protocol& P) {
  EvalResult& r = P.r;
  std::vector<EvalObject> known_list;  // the report's categories are the learnt and tested ones
  for (const EvalObject& o : P.objects)
    if (o.role != EvalRole::kUnknown) known_list.push_back({o.category, o.id, {}, o.source, o.any_pose, o.role});
  r.categories = paper_category_order(known_list);
  std::vector<std::string> cv_categories;
  std::vector<size_t> cv_objects;
  for (size_t i = 0; i < P.objects.size(); ++i) {
    const EvalObject& o = P.objects[i];
    const bool several_sources = std::any_of(P.objects.begin(), P.objects.end(),
                                             [&](const EvalObject& x) { return x.source != P.objects[0].source; });
    r.object_ids.push_back((several_sources ? o.source + ":" : "") + o.category + "/" + o.id);
    if (o.role == EvalRole::kUnknown) {
      auto it = std::find(r.unknown_categories.begin(), r.unknown_categories.end(), o.category);
      if (it == r.unknown_categories.end()) it = r.unknown_categories.insert(it, o.category);
      r.object_truth.push_back(-1);
      r.object_unknown_class.push_back(static_cast<int>(it - r.unknown_categories.begin()));
    } else {
      r.object_truth.push_back(static_cast<int>(
          std::find(r.categories.begin(), r.categories.end(), o.category) - r.categories.begin()));
      r.object_unknown_class.push_back(-1);
    }
    r.object_source.push_back(o.source);
    if (o.role != EvalRole::kUnknown) {
      auto& list = o.role == EvalRole::kTestOnly ? r.test_sources : r.train_sources;
      if (std::find(list.begin(), list.end(), o.source) == list.end()) list.push_back(o.source);
    }
    if (o.any_pose && std::find(r.any_pose_categories.begin(), r.any_pose_categories.end(), o.category) ==
                          r.any_pose_categories.end())
      r.any_pose_categories.push_back(o.category);
    if (o.role == EvalRole::kCrossValidate) {
      cv_categories.push_back(o.category);
      cv_objects.push_back(i);
    }
  }
  r.cross_source = cv_objects.empty();
  r.object_fold.assign(P.objects.size(), -1);
  if (r.cross_source) {
    P.folds = 1;
    for (size_t i = 0; i < P.objects.size(); ++i)
      if (P.objects[i].role == EvalRole::kTestOnly || P.objects[i].role == EvalRole::kUnknown) r.object_fold[i] = 0;
  } else {
    P.folds = P.params.folds;
    r.test_sources = r.train_sources;
    const std::vector<int> f = stratified_folds(cv_categories, P.params.folds, P.params.seed);
    for (size_t j = 0; j < cv_objects.size(); ++j) r.object_fold[cv_objects[j]] = f[j];
    // Objects of no learnt category are dealt to the folds too: each is tested by one fold's model.
    std::vector<std::string> unknown_categories;
    std::vector<size_t> unknown_objects;
    for (size_t i = 0; i < P.objects.size(); ++i)
      if (P.objects[i].role == EvalRole::kUnknown) unknown_categories.push_back(P.objects[i].category), unknown_objects.push_back(i);
    const std::vector<int> u = stratified_folds(unknown_categories, P.params.folds, P.params.seed + 1);
    for (size_t j = 0; j < unknown_objects.size(); ++j) r.object_fold[unknown_objects[j]] = u[j];
  }
}

// ---- 1. full 3D clouds (sec. 3.4) ----
void make_object_clouds(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n = P.objects.size();
  P.full.assign(n, {});
  parallel_for(n, P.threads, "object clouds", P.progress, [&](size_t i) {
    P.full[i] = object_cloud(P.objects[i].mesh, P.params.points_per_object, P.object_seed(i));
  });
  for (const Points& p : P.full) P.r.object_points.push_back(p.size());
  P.r.timings.push_back({"object clouds", seconds_since(t0),
                         P.params.points_per_object ? std::to_string(P.params.points_per_object) + " samples per object"
                                                    : "mesh vertices"});
}

// ---- 2. single views by HPR from the paper's viewpoints; objects without an up in a random pose ----
void make_views(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n = std::clamp<size_t>(P.params.views_per_object, 1, 6);
  P.views.assign(P.objects.size() * n, {});
  // Training-only views from other elevations follow the tested ones (learnt objects only).
  std::vector<float> elevation(P.views.size(), kPaperElevationDeg);
  for (float e : P.params.train_elevations_deg)
    for (size_t o = 0; o < P.objects.size(); ++o)
      if ((P.objects[o].role == EvalRole::kCrossValidate || P.objects[o].role == EvalRole::kTrainOnly) &&
          e != kPaperElevationDeg)
        for (size_t v = 0; v < n; ++v) {
          P.views.push_back({});
          P.views.back().object = static_cast<int>(o), P.views.back().view = static_cast<int>(v);
          P.views.back().train_only = true;
          elevation.push_back(e);
        }
  parallel_for(P.views.size(), P.threads, "HPR views", P.progress, [&](size_t j) {
    if (j < P.objects.size() * n) P.views[j].object = static_cast<int>(j / n), P.views[j].view = static_cast<int>(j % n);
    const size_t o = size_t(P.views[j].object), v = size_t(P.views[j].view);
    const EvalObject& object = P.objects[o];
    P.views[j].cloud =
        object_view(P.full[o], v, n, object.any_pose, P.object_seed(o), P.params.hpr_radius_factor, elevation[j]);
    if ((object.role == EvalRole::kCrossValidate || object.role == EvalRole::kTrainOnly) && P.tp.tilt_deg > 0)
      P.views[j].learnt = training_view(P.views[j].cloud, P.tp, P.object_seed(o) + v);
  });
  size_t posed = 0;
  for (const EvalObject& o : P.objects) posed += o.any_pose;
  P.r.timings.push_back({"HPR views", seconds_since(t0),
                         std::to_string(P.views.size()) + " views" +
                             (P.views.size() > P.objects.size() * n
                                  ? " (" + std::to_string(P.views.size() - P.objects.size() * n) + " for training only)"
                                  : std::string()) +
                             (posed ? ", " + std::to_string(posed) + " objects without an up in random poses" : "")});
}

// ---- 2b. the density each model learns (median relative density of its training views), and the
// test views of a non-ideal condition: the sensor's view, through the filters at that density ----
void trained_densities(Protocol& P) {
  std::vector<double> density(P.views.size(), 0.0);
  parallel_for(P.views.size(), P.threads, "training density", P.progress, [&](size_t v) {
    if (P.learnt(v)) density[v] = relative_density(P.learnt_cloud(v).points);
  });
  for (int fold = 0; fold < P.folds; ++fold) {
    std::vector<double> d;
    for (size_t v = 0; v < P.views.size(); ++v)
      if (P.learnt(v) && P.r.object_fold[size_t(P.views[v].object)] != fold && density[v] > 0) d.push_back(density[v]);
    std::sort(d.begin(), d.end());
    P.r.trained_density.push_back(d.empty() ? 0.0 : d[d.size() / 2]);
  }
}

void sensor_test_views(Protocol& P) {
  const ScanCondition& condition = P.params.test_condition;
  if (condition.is_ideal()) return;
  const auto t0 = Clock::now();
  const size_t n = std::clamp<size_t>(P.params.views_per_object, 1, 6);
  parallel_for(P.views.size(), P.threads, "sensor views", P.progress, [&](size_t v) {
    if (!P.tested(v)) return;
    View& view = P.views[v];
    const size_t o = size_t(view.object);
    if (view.learnt.points.empty()) view.learnt = view.cloud;  // training keeps the ideal view
    view.ideal_points = std::max<size_t>(1, view.cloud.points.size());
    ScanFilterParams fp = P.params.filters;
    fp.relative_density = P.r.trained_density[size_t(P.r.object_fold[o])];
    view.cloud = filter_scan(condition_view(P.objects[o], P.full[o], size_t(view.view), n, P.object_seed(o), condition,
                                            P.params.points_per_object, P.params.hpr_radius_factor),
                             fp);
  });
  P.r.timings.push_back({"sensor views", seconds_since(t0), describe(condition) + ", filtered"});
}

}  // namespace

void eval_internal::compute_slot(Protocol& P, FeatureSlot& slot, const Cloud& cloud) {
  const auto c0 = Clock::now();
  auto f = cloud_features(cloud, P.tp, P.base, 1);
  slot.seconds = seconds_since(c0);
  slot.ok = f.ok();
  if (f.ok()) slot.features = std::move(*f);
  else slot.error = f.error().message;
}

namespace {

// ---- 3. full-view features (and the keypoint cut margin) ----
void full_view_features(Protocol& P) {
  const auto t0 = Clock::now();
  const bool keypoint_stages = std::any_of(P.stages.begin(), P.stages.end(),
                                           [](const Stage& s) { return s.kind == StageKind::kKeypoints; });
  P.slots.assign(P.views.size(), {});
  P.margin.assign(P.views.size(), 0.f);
  parallel_for(P.views.size(), P.threads, "features: full views", P.progress, [&](size_t v) {
    P.slots[v].view = v;
    P.slots[v].count = P.views[v].cloud.points.size();
    if (!P.tested(v) && P.tilted(v)) return;  // only its tilted copy is learnt
    compute_slot(P, P.slots[v], P.views[v].cloud);
    if (keypoint_stages && P.tested(v) && P.views[v].cloud.points.size() > 1) {
      SurfaceParams sp = P.tp.features.surface;
      sp.threads = 1;
      const KdTree tree(P.views[v].cloud.points);
      P.margin[v] = P.params.cut_margin_supports * support_radius(tree, sp);
    }
  });
  double cpu = 0;
  for (const FeatureSlot& s : P.slots) cpu += s.seconds;
  P.r.timings.push_back({"features: full views", seconds_since(t0),
                         std::to_string(P.slots.size()) + " clouds, " +
                             std::to_string(int(1000 * cpu / double(std::max<size_t>(1, P.slots.size())))) + " ms CPU each"});
}

// ---- 4. prefixes: the stage cuts of tested views and the training prefixes of learnt ones, each once ----
void prefix_features(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n_views = P.views.size();
  std::vector<std::map<size_t, int>> slot_of(n_views);
  P.stage_slot.assign(n_views, std::vector<int>(P.stages.size(), -1));
  P.train_slots.assign(n_views, {});
  P.seen_slots.assign(n_views, {});
  std::vector<std::map<size_t, int>> learnt_slot_of(n_views);
  auto slot_for = [&](size_t v, size_t count, bool learnt) -> int {
    if (count == 0) return -1;
    learnt = learnt && P.tilted(v);
    if (!learnt && count >= P.views[v].cloud.points.size()) return static_cast<int>(v);
    auto [it, fresh] = (learnt ? learnt_slot_of : slot_of)[v].emplace(count, static_cast<int>(P.slots.size()));
    if (fresh) {
      P.slots.emplace_back();
      P.slots.back().view = v;
      P.slots.back().count = count;
      P.slots.back().learnt = learnt;
    }
    return it->second;
  };
  for (size_t v = 0; v < n_views; ++v) {
    const Points& pts = P.views[v].cloud.points;
    if (P.tested(v)) {
      std::vector<float> heights;
      for (const Vec3& k : P.slots[v].features.positions) heights.push_back(k.z());
      for (size_t s = 0; s < P.stages.size(); ++s) {
        size_t count = pts.size();
        if (P.stages[s].kind == StageKind::kKeypoints)
          count = keypoint_prefix(pts, heights, static_cast<size_t>(P.stages[s].value), P.margin[v]);
        else if (P.stages[s].kind == StageKind::kFraction)
          count = fraction_prefix(pts.size(), P.full_points(v), P.stages[s].value);
        P.stage_slot[v][s] = slot_for(v, count, false);
      }
    }
    if (P.learnt(v)) {
      const size_t n = P.learnt_cloud(v).points.size();
      // A tilted view is learnt tilted; its held-out calibration decides it as seen (what a test cloud is).
      auto learn = [&](size_t count) {
        const int id = slot_for(v, count, true);
        if (id < 0) return;
        P.train_slots[v].push_back(id);
        P.seen_slots[v].push_back(P.tilted(v) && P.tp.calibration_folds >= 2 ? slot_for(v, count, false) : id);
      };
      learn(n);
      for (double f : P.tp.partial_prefixes) {
        const size_t count = static_cast<size_t>(std::round(f * double(n)));
        if (count < n) learn(count);
      }
    }
  }
  const size_t first = n_views;
  parallel_for(P.slots.size() - first, P.threads, "features: prefixes", P.progress, [&](size_t j) {
    FeatureSlot& slot = P.slots[first + j];
    compute_slot(P, slot, reveal_top_down(slot.learnt ? P.learnt_cloud(slot.view) : P.views[slot.view].cloud, slot.count));
  });
  double cpu = 0;
  for (size_t i = first; i < P.slots.size(); ++i) cpu += P.slots[i].seconds;
  const size_t n = P.slots.size() - first;
  P.r.timings.push_back({"features: prefixes", seconds_since(t0),
                         std::to_string(n) + " distinct prefixes, " +
                             std::to_string(int(1000 * cpu / double(std::max<size_t>(1, n)))) + " ms CPU each"});
}

// ---- stage statistics (over the tested views) ----
void stage_statistics(Protocol& P) {
  EvalResult& r = P.r;
  const size_t n_cat = r.categories.size();
  for (size_t s = 0; s < P.stages.size(); ++s) {
    StageStats st;
    st.stage = stage_name(P.stages[s]);
    st.keypoints.assign(n_cat, 0), st.visible_percent.assign(n_cat, 0), st.failed.assign(n_cat, 0);
    std::vector<size_t> n(n_cat, 0);
    std::set<int> counted;
    size_t total_ok = 0;
    for (size_t v = 0; v < P.views.size(); ++v) {
      if (!P.tested(v) || P.unknown(v)) continue;
      const int c = r.object_truth[static_cast<size_t>(P.views[v].object)];
      const int id = P.stage_slot[v][s];
      if (id < 0 || !P.slots[id].ok) {
        ++st.failed[c];
        continue;
      }
      const FeatureSlot& slot = P.slots[id];
      const double visible = 100.0 * double(slot.count) / double(P.full_points(v));
      st.keypoints[c] += double(slot.features.positions.size());
      st.visible_percent[c] += visible;
      st.mean_keypoints += double(slot.features.positions.size());
      st.mean_visible_percent += visible;
      ++n[c], ++total_ok;
      if (counted.insert(id).second) st.feature_seconds += slot.seconds;
      if (P.stages[s].kind == StageKind::kKeypoints && P.slots[v].features.positions.size() >= P.stages[s].value) {
        const size_t k = slot.features.positions.size();
        st.cut_min_keypoints = st.cut_views ? std::min(st.cut_min_keypoints, k) : k;
        st.cut_max_keypoints = std::max(st.cut_max_keypoints, k);
        st.cut_mean_keypoints += double(k);
        st.cut_visible_percent += visible;
        ++st.cut_views;
      }
    }
    if (st.cut_views) st.cut_mean_keypoints /= double(st.cut_views), st.cut_visible_percent /= double(st.cut_views);
    for (size_t c = 0; c < n_cat; ++c)
      if (n[c]) st.keypoints[c] /= double(n[c]), st.visible_percent[c] /= double(n[c]);
    if (total_ok) st.mean_keypoints /= double(total_ok), st.mean_visible_percent /= double(total_ok);
    r.stage_stats.push_back(std::move(st));
  }
}

// ---- 5. per fold: train on the other folds' (or the training sources') views, classify its test views ----
Status train_and_classify(Protocol& P) {
  EvalResult& r = P.r;
  const size_t n_cat = r.categories.size();
  double train_seconds = 0, classify_seconds = 0;
  size_t train_samples = 0;
  for (int fold = 0; fold < P.folds; ++fold) {
    const std::string tag = r.cross_source ? std::string("all sources") : "fold " + std::to_string(fold + 1) + "/" + std::to_string(P.folds);
    auto t0 = Clock::now();
    if (P.progress) P.progress({tag + ": train", 0, 1});
    std::vector<TrainingSample> samples;
    std::vector<size_t> test_views;
    for (size_t v = 0; v < P.views.size(); ++v) {
      const int o = P.views[v].object;
      if (r.object_fold[static_cast<size_t>(o)] == fold) {
        if (!P.views[v].train_only) test_views.push_back(v);
        continue;
      }
      if (!P.learnt(v)) continue;
      const EvalObject& object = P.objects[static_cast<size_t>(o)];
      const std::string id = object.source + "/" + object.id;
      for (size_t k = 0; k < P.train_slots[v].size(); ++k) {  // the whole (learnt) view, then its prefixes
        const FeatureSlot& slot = P.slots[static_cast<size_t>(P.train_slots[v][k])];
        if (!slot.ok) continue;
        samples.push_back({object.category, id, slot.features, k == 0});
        const FeatureSlot& seen = P.slots[static_cast<size_t>(P.seen_slots[v][k])];
        if (&seen != &slot && seen.ok) samples.back().as_seen = seen.features;
      }
    }
    train_samples += samples.size();
    TrainParams tp = P.tp;  // the model records the density its training views had (scan filters)
    tp.filters.relative_density = r.trained_density[size_t(fold)];
    auto trained = train_on_features(std::move(samples), tp);
    if (!trained.ok()) return Error{trained.error().code, tag + ": training failed: " + trained.error().message};
    const auto model = std::make_shared<const Model>(std::move(*trained));
    P.fold_models.push_back(model);
    r.settle_margins.push_back(model->impl->calibration.settle_margin);
    r.calibration_accuracy.push_back(model->impl->calibration.held_out_accuracy);
    r.novelty_thresholds.push_back(model->impl->calibration.novelty_threshold);
    train_seconds += seconds_since(t0);
    if (P.progress) P.progress({tag + ": train", 1, 1});

    t0 = Clock::now();
    std::vector<int> to_ours;
    for (const std::string& c : model->categories)
      to_ours.push_back(static_cast<int>(std::find(r.categories.begin(), r.categories.end(), c) - r.categories.begin()));
    P.fold_to_ours.push_back(to_ours);
    const ModelImpl& impl = *model->impl;
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
        Classification c;
        c.method = d.method;
        c.winner = argmax(scores);
        judge_unknown(*model, decision, P.slots[id].features, c);
        d.winner = to_ours[c.winner];
        d.novelty = c.novelty;
        d.unknown = c.unknown;
      }
    });
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
    if (P.tested(v) && !P.unknown(v)) tested.push_back(v);
  r.streams.resize(tested.size());
  SessionParams sp = P.params.session;
  sp.method = r.change_method;
  parallel_for(tested.size(), P.threads, "streaming sessions", P.progress, [&](size_t i) {
    const size_t v = tested[i];
    const int o = P.views[v].object, fold = r.object_fold[static_cast<size_t>(o)];
    StreamTrace& t = r.streams[i];
    t.fold = fold, t.object = o, t.view = P.views[v].view, t.truth = r.object_truth[static_cast<size_t>(o)];
    auto session = ScanSession::create(P.fold_models[static_cast<size_t>(fold)], sp);
    if (!session.ok()) return;
    const Cloud& cloud = P.views[v].cloud;
    const std::vector<uint32_t> order = top_down_order(cloud.points);
    const size_t chunk =
        std::max<size_t>(1, static_cast<size_t>(std::lround(P.params.stream_chunk_fraction * double(P.full_points(v)))));
    Cloud part;
    part.sensor = cloud.sensor;
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

// ---- 8. what looks wrong ----
void flag_problems(Protocol& P) {
  EvalResult& r = P.r;
  size_t tested_views = 0;
  for (size_t v = 0; v < P.views.size(); ++v) tested_views += P.tested(v);
  const double chance = 100.0 / double(r.categories.size());
  for (MethodId m : P.params.methods) {
    const Tally t = accuracy(r.decisions, "full", m);
    if (t.total && t.percent() < chance + 10)
      r.notes.push_back(std::string(method_name(m)) + " is near chance on full views (" +
                        std::to_string(int(std::lround(t.percent()))) + " %, chance " +
                        std::to_string(int(std::lround(chance))) + " %).");
  }
  for (size_t s = 0; s < P.params.stages.size(); ++s) {
    const Stage& stage = P.params.stages[s];
    const StageStats& st = r.stage_stats[s];
    size_t failed = 0;
    for (size_t f : st.failed) failed += f;
    if (failed)
      r.notes.push_back("stage " + st.stage + ": features failed on " + std::to_string(failed) + " of " +
                        std::to_string(tested_views) + " views (counted as wrong decisions).");
    if (stage.kind != StageKind::kKeypoints) continue;
    size_t short_views = 0;
    for (size_t v = 0; v < P.views.size(); ++v) short_views += P.tested(v) && P.slots[v].features.positions.size() < stage.value;
    if (short_views)
      r.notes.push_back("stage " + st.stage + ": " + std::to_string(short_views) + " of " + std::to_string(tested_views) +
                        " views have fewer than " + stage_name(stage).substr(0, stage_name(stage).size() - 2) +
                        " keypoints on the full view, so the stage is the full view for them.");
  }
  // Feature errors grouped by their message with the numbers blanked out; the first one shown in full.
  struct ErrorGroup {
    size_t clouds = 0;
    std::string example;
    std::set<std::string> objects;
  };
  std::map<std::string, ErrorGroup> errors;
  for (const FeatureSlot& slot : P.slots) {
    if (slot.ok || slot.error.empty()) continue;  // computed fine, or never needed
    std::string key;
    for (char c : slot.error) {
      const bool digit = std::isdigit(static_cast<unsigned char>(c));
      if (!digit) key += c;
      else if (key.empty() || key.back() != '#') key += '#';
    }
    ErrorGroup& g = errors[key];
    const std::string& object = r.object_ids[static_cast<size_t>(P.views[slot.view].object)];
    if (g.clouds++ == 0)
      g.example = object + " view " + std::to_string(P.views[slot.view].view) + ", " + std::to_string(slot.count) +
                  " points: " + slot.error;
    g.objects.insert(object);
  }
  for (const auto& [key, g] : errors) {
    std::string list;
    for (const std::string& o : g.objects) list += (list.empty() ? "" : ", ") + o;
    r.notes.push_back("features failed on " + std::to_string(g.clouds) + " clouds (views and prefixes) of " +
                      std::to_string(g.objects.size()) + " objects (" + list + "), e.g. " + g.example);
  }
  if (contains(P.params.methods, MethodId::kBoK) || contains(P.params.methods, MethodId::kBoG) ||
      contains(P.params.methods, MethodId::kKGH)) {
    size_t no_keypoints = 0;
    for (size_t v = 0; v < P.views.size(); ++v)
      no_keypoints += P.tested(v) && P.slots[v].ok && P.slots[v].features.positions.empty();
    if (no_keypoints)
      r.notes.push_back(std::to_string(no_keypoints) + " full views have no keypoint at all (BoK/BoG/KGH see nothing).");
  }
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
  P.tp = params.train;
  P.tp.methods = params.methods;
  P.tp.seed = params.seed;
  P.tp.threads = P.threads;
  if (!contains(P.tp.methods, P.tp.default_method)) P.tp.default_method = P.tp.methods.front();
  P.base = base_methods(P.tp);
  P.r.grid = exploration_grid(params.explore_max_keypoints, params.explore_step);
  P.stages = params.stages;
  for (size_t g : P.r.grid)
    if (const Stage s{StageKind::kKeypoints, double(g)}; std::find(P.stages.begin(), P.stages.end(), s) == P.stages.end())
      P.stages.push_back(s);

  assign_folds(P);
  make_object_clouds(P);
  make_views(P);
  trained_densities(P);
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
