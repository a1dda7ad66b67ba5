// The benchmarks' training set: the zoo's objects seen as the recipe sees them (the paper's six ideal
// views given, the training cameras' views augmented), as glimpse train sends them.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "glimpse/learning/model.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/views/zoo.h"

namespace glimpse::bench {

// The category of a zoo category's object `index` (0, 1, ... in the zoo's order) when each zoo category is
// dealt into `groups` categories "chair.0", "chair.1", ... (object i in group i % groups); the zoo
// category itself when groups <= 1.
inline std::string grouped_category(const std::string& category, size_t index, size_t groups) {
  return groups > 1 ? category + "." + std::to_string(index % groups) : category;
}

// per_category of each of the zoo's categories (seed 42), thinned to a fixed density: the zoo's ideal
// views' median (glimpse train measures it in a pass); each zoo category dealt into `groups` categories.
inline std::vector<TrainingCloud> zoo_training_set(size_t per_category, size_t groups = 1) {
  ViewRecipe recipe;
  recipe.train_sensors = default_training_sensors();
  std::vector<TrainingCloud> out;
  std::map<std::string, size_t> seen;
  for (const LabelledMesh& object : make_zoo(per_category, 42)) {
    const std::string category = grouped_category(object.category, seen[object.category]++, groups);
    const std::string key = object.category + "/" + object.id;
    const ObjectViews views = training_views(object.mesh, key, object.any_pose, recipe, 3363.8);
    for (size_t v = 0; v < views.views.size(); ++v)
      if (!views.views[v].points.empty()) out.push_back({category, key, views.views[v], v >= views.first_augmented});
  }
  return out;
}

}  // namespace glimpse::bench
