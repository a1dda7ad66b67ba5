// A cloud's scores under a model (sec. 3.3, 4): each base method's global histogram, its decision stage's
// scores and nearest references, and the fusion's mean with its logistic decision's share.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "glimpse/features/method_features.h"
#include "glimpse/learning/decision.h"
#include "glimpse/learning/model_internals.h"

namespace glimpse {

// The global histogram of one base method (every method but fusion).
Eigen::VectorXd method_histogram(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

// The components of the fusion its logistic decision reads (every one but the size-only baseline),
// and a cloud's mapped features from their histograms (`histogram(m)` of each).
std::vector<MethodId> fusion_head_methods(const ModelImpl& impl);
Eigen::VectorXd fusion_head_features(const ModelImpl& impl, const std::function<Eigen::VectorXd(MethodId)>& histogram);
// Per row (of category labels[i]), whether the logistic decision learns it: at most `per_category` rows of
// each category, those of the smallest seeded hash of their key (CalibrationRows::keys; every row when
// per_category <= 0).
std::vector<uint8_t> fusion_head_learns(const std::vector<int>& labels, const std::vector<uint64_t>& keys,
                                        int categories, int per_category, uint64_t seed);
// The mapped features of every row of `histograms` (indexed by MethodId, rows aligned; `rows` empty: all),
// rows shared among `threads` (<= 0: all).
Eigen::MatrixXd fusion_head_rows(const ModelImpl& impl, const std::vector<Eigen::MatrixXd>& histograms,
                                 const std::vector<Eigen::Index>& rows, int threads);
// The fusion's scores: the mean of its components' scores, with `share` of the head's probabilities
// (`probabilities` empty or share 0: the mean alone).
Eigen::VectorXd fused_scores(const Eigen::VectorXd& mean, const Eigen::VectorXd& probabilities, double share);

// Scores of `method` (fusion: the mean of its components' scores, with the head's share).
Eigen::VectorXd method_scores(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

// One component's nearest references: per category, the cloud's distance to it (over its
// `objects` nearest training objects, nearest_objects_distance) and whether its nearest reference is a
// whole training cloud (1) or a top-down prefix (0), whose typical distances differ (Calibration).
struct NearestReferences {
  Eigen::VectorXd distance;
  std::vector<uint8_t> whole;
  double residual = 0;  // StageScores::residual
};
NearestReferences nearest_references(const DecisionStage& stage, StageScores&& scores,
                                     const std::vector<uint8_t>& reference_whole,
                                     const std::vector<uint32_t>& reference_object, const std::vector<int>& objects);

// The scores of `method` with the novelty of each category (empty when `method` was not calibrated
// for novelty: only the model's default method is). The decision's novelty is that of its winner.
struct MethodDecision {
  Eigen::VectorXd scores;
  Eigen::VectorXd novelty;
};
MethodDecision method_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

}  // namespace glimpse
