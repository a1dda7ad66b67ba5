// What train() (training_clouds.cpp) and train_on_features (training.cpp) refuse before learning
// anything: no clouds, no method, a cloud without a category, fewer than 2 categories, parameters out of
// range.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/train_params.h"

namespace glimpse {

// Sample: TrainingCloud or TrainingSample (a category each).
template <class Sample>
Status check_training_set(const std::vector<Sample>& data, const TrainParams& params) {
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

}  // namespace glimpse
