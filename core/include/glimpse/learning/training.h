// Training from clouds whose features are computed (train() in model.h computes them; the lab computes
// each view's features once and trains every fold from them): codebooks, decision stages, the fusion's
// logistic decision, calibration and the novelty model.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/features/method_features.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"

namespace glimpse {

// The base methods (every one but fusion) whose features and stages params.methods need: the
// methods themselves and, with fusion, its components.
std::vector<MethodId> base_methods(const TrainParams& params);

// A training cloud as it is learnt: turned by a random tilt of up to params.tilt_deg (seeded by
// params.seed and `salt`); its top-down prefixes are cut from this turned cloud.
Cloud training_view(const Cloud& cloud, const TrainParams& params, uint64_t salt);

// A training cloud whose features are already computed (train() computes them; the evaluation
// computes each view's features once and trains every fold from them).
struct TrainingSample {
  std::string category;
  std::string object_id;
  CloudFeatures features;
  bool whole = true;  // the whole training cloud, not one of its top-down prefixes
  // The same cloud as a sensor gives it, when what is learnt differs (training views are tilted, see
  // TrainParams::tilt_deg): calibration decides these held-out clouds, as a test cloud would come.
  std::optional<CloudFeatures> as_seen;
  bool augmented = false;  // TrainingCloud::augmented
};
// `start`: a model learnt from related rows (the base a model grows from, of the same parameters): the
// logistic decisions' solvers (the model's, its calibration folds', its novelty model's) start at its
// heads, by category name, and stop at the same tolerance in fewer steps; the model learnt is the one a
// start from zero gives, to within that tolerance.
Expected<Model> train_on_features(std::vector<TrainingSample> samples, const TrainParams& params,
                                  const ProgressFn& progress = {}, const CancelFn& cancel = {},
                                  const Model* start = nullptr);

}  // namespace glimpse
