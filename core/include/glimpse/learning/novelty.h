// "None of these": how novel a cloud is for each category (its distance to the category's nearest
// training objects and what the decision stage's PCA leaves out, over their calibrated scales), and the
// answer's unknown, its reason and the size rule.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/features/method_features.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/scores.h"

namespace glimpse {

// Per category, the sum (Calibration::novelty_adds_evidence; else the larger) of two means over the
// components, each over its calibrated scale (Calibration::novelty_scale): the distance to the
// category's nearest reference, and what the stage's PCA leaves out of the histogram; divided by
// `scores` (the decision's, per category) when Calibration::novelty_over_score. Empty when not
// calibrated or the sizes differ.
Eigen::VectorXd category_novelty(const Calibration& c, const std::vector<NearestReferences>& components,
                                 const Eigen::VectorXd& scores);
// A cloud's novelty joined with its top-down prefix's (TrainParams::novelty_prefix): per category, their
// geometric mean. `whole` alone when `prefix` is empty or of another size.
Eigen::VectorXd joint_novelty(const Eigen::VectorXd& whole, const Eigen::VectorXd& prefix);
// novelty, unknown and unknown_reason of `c` (its method and winner set) from `decision` on `f`, at the
// model's default operating point: what classify answers (the lab and sessions' final answer share it).
void judge_unknown(const Model& model, const MethodDecision& decision, const CloudFeatures& f, Classification& c);
// judge_unknown after the size rule: warning and outside_learnt_sizes from `points`, the cloud decided
// (after the filters), as classify and a session's final answer judge it.
void judge_cloud(const Model& model, const MethodDecision& decision, const CloudFeatures& f, const Cloud& points,
                 Classification& c);
// Why `method` cannot judge the features at all (a keypoint method with no keypoint); empty if it can.
std::string cannot_judge(MethodId method, const std::vector<MethodId>& components, const CloudFeatures& f);

}  // namespace glimpse
