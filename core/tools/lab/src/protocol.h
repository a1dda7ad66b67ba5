// The evaluation protocol's shared state and helpers (protocol.cpp runs the phases; robustness.cpp adds
// the robustness matrix with the same views, features and models) and the report's sections.
#pragma once

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "glimpse/lab/evaluation.h"
#include "glimpse/views/sampling.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/novelty.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/learning/scores.h"
#include "glimpse/learning/training.h"

namespace glimpse::eval_internal {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

inline bool contains(const std::vector<MethodId>& v, MethodId m) { return std::find(v.begin(), v.end(), m) != v.end(); }

// The base methods whose features the evaluated methods need (fusion brings its components).
inline std::vector<MethodId> feature_methods(const TrainParams& tp) {
  std::vector<MethodId> base;
  auto add = [&](MethodId m) {
    if (m != MethodId::kFusion && !contains(base, m)) base.push_back(m);
  };
  for (MethodId m : tp.methods) add(m);
  if (contains(tp.methods, MethodId::kFusion))
    for (MethodId m : tp.fusion_of) add(m);
  return base;
}

// body(i) for i in [0, n) on `threads` threads; progress is reported from thread 0 only.
template <class Body>
void parallel_for(size_t n, int threads, const std::string& phase, const EvalProgressFn& progress, Body&& body) {
  std::atomic<size_t> done{0};
  if (progress) progress({phase, 0, n});
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int64_t i = 0; i < static_cast<int64_t>(n); ++i) {
    body(static_cast<size_t>(i));
    const size_t d = ++done;
    if (progress && omp_get_thread_num() == 0) progress({phase, d, n});
  }
  if (progress) progress({phase, n, n});
}

struct View {
  int object = 0;
  int view = 0;  // index among the object's evaluated viewpoints
  bool train_only = false;  // a training view from another elevation or sensor: never tested
  int train_condition = -1;  // >= 0: taken by EvalParams::train_conditions[this] (made in sensor_training_views)
  Cloud cloud;   // as the sensor saw it: what is tested
  Cloud learnt;  // as training learns it (training_view: tilted); empty when that is `cloud` itself
  // The ideal view's size when `cloud` was taken by another sensor (0: `cloud` is the ideal view): the
  // stage fractions of a sensor's view are the same share of its points as of the ideal view's.
  size_t ideal_points = 0;
};

// The features of one top-down prefix of one view (count == view size: the full view), cut from the
// view as seen or from its learnt (tilted) copy.
struct FeatureSlot {
  size_t view = 0;
  size_t count = 0;
  bool learnt = false;
  bool ok = false;
  CloudFeatures features;
  std::string error;
  double seconds = 0;
};

// What the phases share.
struct Protocol {
  const std::vector<EvalObject>& objects;
  const EvalParams& params;
  const EvalProgressFn& progress;
  int threads = 1;
  TrainParams tp{};
  MethodFeatureParams features{};  // method_feature_params(tp)
  ViewRecipe recipe{};  // every object's views (learning/object_views.h); train-only views for learnt objects
  std::vector<MethodId> base{};
  int folds = 1;  // models trained: the CV folds, or 1 for a cross-source evaluation
  std::vector<Points> full{};  // full 3D cloud per object (sec. 3.4)
  std::vector<View> views{};
  // Per object: the slots in `views` of its views past the tested ones, in ideal_views' order (other
  // elevations), and of its sensors' training views, in sensor_views' order.
  std::vector<std::vector<size_t>> elevation_slots{}, sensor_slots{};
  std::vector<FeatureSlot> slots{};  // [0, views.size()): the full views; then the distinct prefixes
  std::vector<float> margin{};  // keypoint cut margin per view
  std::vector<Stage> stages{};  // the main stages, then the exploration grid's
  std::vector<std::vector<int>> stage_slot{};  // [view][stage] -> slot, -1 none
  std::vector<std::vector<int>> train_slots{};  // [view] -> slots trained on: the full view, then prefixes
  std::vector<std::vector<int>> seen_slots{};  // [view] -> the same clouds as seen (untilted): calibration's queries
  std::vector<std::shared_ptr<const Model>> fold_models{};
  std::vector<std::vector<int>> fold_to_ours{};  // per fold: model category index -> report category index
  EvalResult r{};

  bool tested(size_t v) const { return !views[v].train_only && r.object_fold[static_cast<size_t>(views[v].object)] >= 0; }
  bool learnt(size_t v) const { return learnt_object(static_cast<size_t>(views[v].object)); }
  bool unknown(size_t v) const { return r.object_truth[static_cast<size_t>(views[v].object)] < 0; }
  // The full 3D cloud's size the view's visible fractions refer to, scaled to a sensor view's density.
  size_t full_points(size_t v) const {
    const double n = double(full[static_cast<size_t>(views[v].object)].size());
    const View& w = views[v];
    return std::max<size_t>(1, size_t(std::llround(w.ideal_points ? n * double(w.cloud.points.size()) / double(w.ideal_points) : n)));
  }
  const Cloud& learnt_cloud(size_t v) const { return views[v].learnt.points.empty() ? views[v].cloud : views[v].learnt; }
  bool tilted(size_t v) const { return !views[v].learnt.points.empty(); }
  std::string key(size_t o) const { return objects[o].category + "/" + objects[o].id; }
  uint64_t object_seed(size_t o) const { return glimpse::object_seed(params.seed, key(o)); }
  bool learnt_object(size_t o) const {
    return objects[o].role == EvalRole::kCrossValidate || objects[o].role == EvalRole::kTrainOnly;
  }
  // A view learnt as augmented (TrainingCloud::augmented) when the models have novelty models: a simulated
  // sensor's training view, or a zoo object's view when the zoo is added to real objects.
  bool augmented(size_t v) const {
    const EvalObject& object = objects[static_cast<size_t>(views[v].object)];
    return views[v].train_condition >= 0 || (zoo_added && object.source == "zoo");
  }
  bool zoo_added = false;  // the zoo's objects learnt beside real ones (--also-train zoo:N)
};

void compute_slot(Protocol& P, FeatureSlot& slot, const Cloud& cloud);

// The protocol's phases before training (protocol_views.cpp, protocol_features.cpp), in the order
// run_evaluation calls them.
Status validate(const std::vector<EvalObject>& objects, const EvalParams& p);
void assign_folds(Protocol& P);        // 0. categories, folds, sources
void make_object_clouds(Protocol& P);  // 1. full 3D clouds (sec. 3.4)
void make_views(Protocol& P);          // 2. single views by HPR from the paper's viewpoints
void trained_densities(Protocol& P);   // 2b. the density each model learns
void sensor_training_views(Protocol& P);  // 2b. training-only views of simulated sensors, filtered
void sensor_test_views(Protocol& P);   // 2b. test views of a non-ideal condition (--sensor), filtered
void full_view_features(Protocol& P);  // 3. full-view features and the keypoint cut margin
void prefix_features(Protocol& P);     // 4. stage cuts and training prefixes
void stage_statistics(Protocol& P);    // over the tested views
// Phase 8 (protocol_problems.cpp): what looks wrong, as the report's notes.
void flag_problems(Protocol& P);
// Phase 9: the robustness matrix (params.matrix) with the trained fold models.
void robustness_matrix(Protocol& P);
// The report's sections on a sensor's test views and on the robustness matrix ("" when neither).
std::string robustness_section(const EvalResult& r);
// report_protocol.cpp: the protocol table, every setting beside the paper's.
std::string protocol_section(const EvalResult& r);
// report_ablations.cpp: "How much is size", keypoints per view, the keypoint ablation.
std::string size_section(const EvalResult& r);
std::string keypoints_section(const EvalResult& r);
std::string keypoint_ablation_section(const EvalResult& r);
// report_streams.cpp: category changes along the exploration, streams' settling.
std::string changes_section(const EvalResult& r);
std::string streams_section(const EvalResult& r);

}  // namespace glimpse::eval_internal
