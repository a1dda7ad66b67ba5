// run_evaluation's data, phases 0-2 (protocol.cpp runs them in order): the objects checked,
// categories and folds, every object's full 3D cloud (sec. 3.4), its single views from the paper's
// viewpoints, the density each model learns, and test views from a simulated sensor when asked.
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "glimpse/lab/evaluation.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/exploration.h"
#include "protocol.h"
#include "glimpse/threads.h"

namespace glimpse {

using namespace eval_internal;

Status eval_internal::validate(const std::vector<EvalObject>& objects, const EvalParams& p) {
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
void eval_internal::assign_folds(Protocol& P) {
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
void eval_internal::make_object_clouds(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n = P.objects.size();
  P.full.assign(n, {});
  parallel_for(n, P.threads, "object clouds", P.progress,
               [&](size_t i) { P.full[i] = full_cloud(P.objects[i].mesh, P.key(i), P.recipe); });
  for (const Points& p : P.full) P.r.object_points.push_back(p.size());
  P.r.timings.push_back({"object clouds", seconds_since(t0),
                         P.params.points_per_object ? std::to_string(P.params.points_per_object) + " samples per object"
                                                    : "mesh vertices"});
}

// ---- 2. single views by HPR from the paper's viewpoints; objects without an up in a random pose ----
// The tested views first (object by object), then the training-only views of learnt objects from other
// elevations (elevation, object, view), then the slots of the simulated sensors' training views
// (sensor, object, view), which sensor_training_views fills once the density they are thinned to is known.
void eval_internal::make_views(Protocol& P) {
  const auto t0 = Clock::now();
  const size_t n = P.recipe.views, objects = P.objects.size();
  P.views.assign(objects * n, {});
  for (size_t j = 0; j < P.views.size(); ++j) P.views[j].object = static_cast<int>(j / n), P.views[j].view = static_cast<int>(j % n);
  auto add_training_only = [&](size_t o, size_t v, int condition, std::vector<std::vector<size_t>>& slots) {
    slots[o].push_back(P.views.size());
    P.views.push_back({});
    P.views.back().object = static_cast<int>(o), P.views.back().view = static_cast<int>(v);
    P.views.back().train_only = true;
    P.views.back().train_condition = condition;
  };
  P.elevation_slots.assign(objects, {});
  P.sensor_slots.assign(objects, {});
  for (float e : P.recipe.train_elevations_deg)
    if (e != kPaperElevationDeg)
      for (size_t o = 0; o < objects; ++o)
        if (P.learnt_object(o))
          for (size_t v = 0; v < n; ++v) add_training_only(o, v, -1, P.elevation_slots);
  for (size_t c = 0; c < P.recipe.train_sensors.size(); ++c)
    for (size_t o = 0; o < objects; ++o)
      if (P.learnt_object(o))
        for (size_t v = 0; v < n; ++v) add_training_only(o, v, static_cast<int>(c), P.sensor_slots);
  parallel_for(objects, P.threads, "HPR views", P.progress, [&](size_t o) {
    ViewRecipe recipe = P.recipe;
    if (!P.learnt_object(o)) recipe.train_elevations_deg.clear();
    std::vector<Cloud> views = ideal_views(P.full[o], P.key(o), P.objects[o].any_pose, recipe);
    for (size_t k = 0; k < views.size(); ++k) {
      View& view = P.views[k < n ? o * n + k : P.elevation_slots[o][k - n]];
      view.cloud = std::move(views[k]);
      if (P.learnt_object(o) && P.tp.tilt_deg > 0)
        view.learnt = training_view(view.cloud, P.tp, P.object_seed(o) + size_t(view.view));
    }
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

// ---- 2b. the density each model learns (median relative density of its ideal training views as learnt), the
// simulated sensors' training views and the test views of a non-ideal condition, each through the
// filters at that density ----
void eval_internal::trained_densities(Protocol& P) {
  std::vector<double> density(P.views.size(), 0.0);
  parallel_for(P.views.size(), P.threads, "training density", P.progress, [&](size_t v) {
    if (P.learnt(v)) density[v] = relative_density(P.learnt_cloud(v).points);
  });
  for (int fold = 0; fold < P.folds; ++fold) {
    std::vector<double> d;
    for (size_t v = 0; v < P.views.size(); ++v)
      if (P.learnt(v) && P.r.object_fold[size_t(P.views[v].object)] != fold) d.push_back(density[v]);
    P.r.trained_density.push_back(median_density(std::move(d)));
  }
}

// A learnt object's sensor views are thinned to the density its models classify at: the model's, or in
// cross-validation the mean of those of the folds that learn it (the views are made once for all folds).
void eval_internal::sensor_training_views(Protocol& P) {
  if (P.params.train_conditions.empty()) return;
  const auto t0 = Clock::now();
  std::vector<double> density(P.objects.size(), 0.0);
  for (size_t o = 0; o < P.objects.size(); ++o) {
    int models = 0;
    for (int fold = 0; fold < P.folds; ++fold)
      if (P.r.object_fold[o] != fold && P.r.trained_density[size_t(fold)] > 0)
        density[o] += P.r.trained_density[size_t(fold)], ++models;
    if (models) density[o] /= models;
  }
  parallel_for(P.objects.size(), P.threads, "sensor training views", P.progress, [&](size_t o) {
    if (P.sensor_slots[o].empty()) return;
    std::vector<Cloud> views = sensor_views(P.objects[o].mesh, P.full[o], P.key(o), P.objects[o].any_pose, P.recipe, density[o]);
    for (size_t k = 0; k < views.size(); ++k) {
      View& view = P.views[P.sensor_slots[o][k]];
      view.cloud = std::move(views[k]);
      if (P.tp.tilt_deg > 0 && !view.cloud.points.empty())
        view.learnt = training_view(view.cloud, P.tp, P.object_seed(o) + 1000 * size_t(view.train_condition + 1) + size_t(view.view));
    }
  });
  size_t taken = 0;
  for (const View& view : P.views) taken += view.train_condition >= 0;
  const std::string detail = describe(P.params.train_conditions);
  P.r.timings.push_back({"sensor training views", seconds_since(t0), std::to_string(taken) + " views: " + detail + ", filtered to the trained density"});
}

void eval_internal::sensor_test_views(Protocol& P) {
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
    view.cloud = filter_scan(condition_view(P.objects[o].mesh, P.objects[o].any_pose, P.full[o], size_t(view.view), n, P.object_seed(o), condition,
                                            P.params.points_per_object, P.params.hpr_radius_factor),
                             fp);
  });
  P.r.timings.push_back({"sensor views", seconds_since(t0), describe(condition) + ", filtered"});
}

}  // namespace glimpse
