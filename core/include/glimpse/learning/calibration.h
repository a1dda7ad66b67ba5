// Calibration: what a model learns about its own decisions from held-out folds of its training set (inner
// cross-validation by object), so that no threshold is set on the clouds it will be judged on: the score
// margin at which a streamed decision settles, the share of the fusion's logistic decision, and how far
// from anything learnt its known clouds fall ("none of these").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/model_internals.h"

namespace glimpse {

// The training rows calibration decides again, held out: every row is a training cloud (a view or one of
// its top-down prefixes) of one object.
struct CalibrationRows {
  // [MethodId]: the rows' histograms as the decision stages learn them.
  std::vector<Eigen::MatrixXd> histograms;
  // [MethodId]: the same rows as a sensor gives them (untilted: TrainParams::tilt_deg), what a held-out row
  // is decided on. Empty: the rows as learnt.
  std::vector<Eigen::MatrixXd> as_seen;
  // [MethodId]: row i's own top-down prefix (CloudFeatures::top_prefix), whose novelty joins the row's,
  // where has_prefix[i]; has_prefix empty: none.
  std::vector<Eigen::MatrixXd> prefix_histograms;
  std::vector<uint8_t> has_prefix;
  std::vector<int> labels;   // per row: its category
  std::vector<int> objects;  // per row: its object (0, 1, ...)
  std::vector<uint8_t> whole;  // per row: a whole cloud (1) or a top-down prefix (0)
  std::vector<std::string> object_categories;  // per object
  int categories = 0;
  // Per row: whether the fusion's logistic decision learns it (TrainParams::fusion_head_rows_per_category);
  // empty: every row.
  std::vector<uint8_t> head_learns;
  // Per row: a hash of its object's category and name and its place among the object's rows, what rows
  // are sampled by: the same row keeps its key when other objects join the training set.
  std::vector<uint64_t> keys;

  const std::vector<Eigen::MatrixXd>& queries() const { return as_seen.empty() ? histograms : as_seen; }
};

// Inner cross-validation of `method`'s decision stages over params.calibration_folds folds of the training
// objects. The codebooks are the model's own (fitted without labels). Without `measure_novelty` no novelty
// is calibrated (nor any prefix decided): the settle margin, the head's share and the held-out accuracy
// are the same. A cancel stops it between inner folds with what it has (the caller then stores nothing).
// `fold_done(k, folds)` after each inner fold: long trainings report where calibration is.
// `fold_heads`, when given: per inner fold, where its logistic decision's solver starts (empty, or a fold
// without one: the model's own head), replaced by the heads the folds learnt.
Calibration calibrate(const ModelImpl& impl, MethodId method, const CalibrationRows& rows, bool measure_novelty,
                      int threads, const CancelFn& cancel = {},
                      const std::function<void(size_t, size_t)>& fold_done = {},
                      std::vector<Chi2Logistic>* fold_heads = nullptr);

// Inner folds of the training objects (stratified_folds, model.h), each category's round robin starting
// at a fold drawn from its name, so a category added to the training set moves no other's objects.
std::vector<int> calibration_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed);

}  // namespace glimpse
