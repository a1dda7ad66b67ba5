// What a trained Model holds beyond its public summary (model.h): codebooks, decision stages, the fusion's
// logistic decision, calibration and the novelty model. Training fills it; classification, sessions,
// serialisation and the lab read it.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "glimpse/features/method_features.h"
#include "glimpse/features/methods.h"
#include "glimpse/learning/chi2_logistic.h"
#include "glimpse/learning/classifiers.h"
#include "glimpse/learning/decision.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"

namespace glimpse {

struct ModelImpl {
  TrainParams params;
  Calibration calibration;
  KeypointCodebook bok;        // sec. 3.2.5, one codebook per method (the paper's cluster counts differ)
  KeypointCodebook bog;
  KeypointCodebook kgh;
  GraphVocabulary graphs;
  float kgh_max_distance_m = 1;
  std::array<std::optional<DecisionStage>, kMethodCount> stages;  // indexed by MethodId; never kFusion
  // The fusion's logistic decision over its components' histograms (fusion_head_methods), its share of
  // the fusion's scores in calibration.fusion_head_share. None: a model of format 6 or older, or trained
  // without one.
  std::optional<Chi2Logistic> fusion_head;
  // The same decision learnt in each inner calibration fold (on the other folds' rows), where a model grown
  // from this one starts its folds' solvers (format 13 on; empty: a model of format 12 or older).
  std::vector<Chi2Logistic> fold_heads;
  // What novelty ("none of these") measures a cloud against when some training clouds were augmented
  // (TrainingCloud::augmented): the same training on the other clouds alone (its stages, its calibrated
  // novelty and threshold; the same categories, nothing nested further). A decision stage fitted with the
  // augmented clouds spans them too, and what it calls near grows with it (docs/open-set.md). None:
  // nothing augmented (novelty from this model's own stages), or a model of format 7 or older.
  std::shared_ptr<const ModelImpl> novelty;
};

// The calibration novelty and its threshold come from: the novelty model's, else the model's own.
inline const Calibration& novelty_calibration(const ModelImpl& impl) {
  return impl.novelty ? impl.novelty->calibration : impl.calibration;
}

// The methods a model needs computed for `method` (fusion expands to its components).
std::vector<MethodId> component_methods(const ModelImpl& impl, MethodId method);

// The features `method` is computed with under this model: its parameters, with the top-down prefix
// only where a calibrated novelty of `method` reads it.
MethodFeatureParams feature_params_for(const ModelImpl& impl, MethodId method);

}  // namespace glimpse
