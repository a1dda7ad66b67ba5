// The model a scenes run classifies with: the learnt objects' views as the evaluation protocol makes them
// (learning/object_views.h: ideal views, then the training sensors' thinned to the ideal views' median
// density) learnt by core's train(), the training glimpse train runs through the service.
#include <omp.h>

#include <algorithm>

#include "glimpse/geometry/scan_filters.h"
#include "glimpse/lab/scenes.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/learning/training.h"
#include "glimpse/threads.h"

namespace glimpse {

namespace {

bool learnt(const EvalObject& o) { return o.role == EvalRole::kTrainOnly || o.role == EvalRole::kCrossValidate; }

// The recipe run_evaluation makes every object's views with.
ViewRecipe recipe_of(const EvalParams& params) {
  ViewRecipe recipe;
  recipe.points = params.points_per_object;
  recipe.views = std::clamp<size_t>(params.views_per_object, 1, 6);
  recipe.hpr_radius_factor = params.hpr_radius_factor;
  recipe.seed = params.seed;
  recipe.train_elevations_deg = params.train_elevations_deg;
  recipe.train_sensors = params.train_conditions;
  recipe.filters = params.filters;
  return recipe;
}

template <class Body>
void for_each_object(size_t n, int threads, const std::string& phase, const EvalProgressFn& progress, Body&& body) {
  if (progress) progress({phase, 0, n});
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int64_t i = 0; i < int64_t(n); ++i) body(size_t(i));
  if (progress) progress({phase, n, n});
}

}  // namespace

Expected<Model> train_lab_model(const std::vector<EvalObject>& objects, const EvalParams& params,
                                const EvalProgressFn& progress) {
  std::vector<const EvalObject*> learn;
  for (const EvalObject& o : objects)
    if (learnt(o)) learn.push_back(&o);
  if (learn.empty()) return invalid_argument("no object to learn");
  if (params.methods.empty()) return invalid_argument("no method to learn");
  const bool zoo_added = std::any_of(learn.begin(), learn.end(), [](const EvalObject* o) { return o->source != "zoo"; });
  const ViewRecipe recipe = recipe_of(params);
  const int threads = resolve_threads(params.threads);
  const size_t n = learn.size();
  auto key = [&](size_t i) { return learn[i]->category + "/" + learn[i]->id; };
  std::vector<Points> full(n);
  std::vector<std::vector<Cloud>> ideal(n), sensors(n);
  std::vector<std::vector<double>> density(n);
  for_each_object(n, threads, "ideal views", progress, [&](size_t i) {
    full[i] = full_cloud(learn[i]->mesh, key(i), recipe);
    ideal[i] = ideal_views(full[i], key(i), learn[i]->any_pose, recipe);
    for (const Cloud& view : ideal[i]) density[i].push_back(relative_density(view.points));
  });
  std::vector<double> all;
  for (const std::vector<double>& d : density) all.insert(all.end(), d.begin(), d.end());
  const double trained_density = median_density(std::move(all));
  if (!recipe.train_sensors.empty())
    for_each_object(n, threads, "sensor training views", progress, [&](size_t i) {
      sensors[i] = sensor_views(learn[i]->mesh, full[i], key(i), learn[i]->any_pose, recipe, trained_density);
    });
  std::vector<TrainingCloud> data;
  for (size_t i = 0; i < n; ++i) {
    const std::string id = learn[i]->source + "/" + key(i);  // the zoo's ids repeat per category
    const bool augmented_object = zoo_added && learn[i]->source == "zoo";
    for (Cloud& view : ideal[i])
      if (!view.points.empty()) data.push_back({learn[i]->category, id, std::move(view), augmented_object});
    for (Cloud& view : sensors[i])
      if (!view.points.empty()) data.push_back({learn[i]->category, id, std::move(view), true});
  }
  TrainParams tp = params.train;
  tp.methods = params.methods;
  tp.seed = params.seed;
  tp.threads = threads;
  if (std::find(tp.methods.begin(), tp.methods.end(), tp.default_method) == tp.methods.end())
    tp.default_method = tp.methods.front();
  tp.filters.relative_density = trained_density;  // the density the model classifies at, as eval's models
  ProgressFn train_progress;
  if (progress)
    train_progress = [&progress](const TrainingProgress& p) { progress({"train: " + p.stage, p.done, p.total}); };
  return train(data, tp, train_progress);
}

}  // namespace glimpse
