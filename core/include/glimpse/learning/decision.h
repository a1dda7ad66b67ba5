// The Bag-of-Features decision stage (sec. 3.3.2-3.3.3, 4): histograms of any method -> PCA -> the
// nearest centre, training vector or k neighbours in L1 -> scores per category, with the distances a
// novelty score is made of.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "glimpse/learning/codebook.h"
#include "glimpse/expected.h"
#include "glimpse/learning/train_params.h"

namespace glimpse {

struct DecisionStage {
  DecisionRule kind = DecisionRule::kNearestNeighbours;
  int categories = 0;
  int neighbours = 5;
  Pca pca;                     // of the training histograms
  Eigen::MatrixXd references;  // centres or training vectors, in PCA space (rows), binary16 values (stored_precision)
  std::vector<int> labels;     // category of each reference
  double temperature = 1;      // L1 distance scale turning distances into scores (see fit_decision)
  bool projected = true;       // false: no PCA (the identity), references are histograms
};
// True when the stage's PCA is the identity (fit_decision without PCA; checked once on a read model).
bool is_identity_projection(const Pca& pca);
// A stage's references at the precision a model stores them: binary16 when every value is finite and within
// its range, else binary32 (fit_decision's references, so a model read back decides as the one trained).
Eigen::MatrixXd stored_precision(const Eigen::MatrixXd& references);
// Whether every value, at binary32, is a binary16 value: a model stores such references in 2 bytes a value
// and loses nothing its binary32 storage would keep.
bool is_binary16(const Eigen::MatrixXd& m);

// `labels` in [0, categories); every category must have at least one row. `groups` (optional, one per
// row): the training object of each row. The score temperature is the median distance from a training
// vector to the nearest one of ANOTHER object, the distance at which an unseen object is met (views
// and prefixes of one object are far closer to each other and would make every score sound certain).
Expected<DecisionStage> fit_decision(const Eigen::MatrixXd& histograms, const std::vector<int>& labels,
                                     int categories, const DecisionParams& params, uint64_t seed, int threads,
                                     const std::vector<int>& groups = {});
// Scores per category in [0, 1], summing to 1 (L1 distances, sec. 4). `by_shape` (a stage without PCA
// only): the histogram and every reference divided by their L1 mass first, so only the proportions of
// the words count (the paper's early-exploration normalisation, sec. 4).
Eigen::VectorXd decide(const DecisionStage& stage, const Eigen::VectorXd& histogram, bool by_shape = false);
// The scores with, per category, the L1 distance (in the stage's PCA space) to its nearest reference,
// which the scores are made of: how far the cloud is from anything of the category learnt, what a
// novelty score ("none of these") measures an answer against. Computed once, for the cost of decide.
struct StageScores {
  Eigen::VectorXd scores;
  Eigen::VectorXd nearest_distance;
  Eigen::VectorXi nearest_reference;  // per category: the row of stage.references it was measured to
  // L1 norm of what the stage's PCA leaves out of the histogram (histogram - mean - its projection back):
  // large for a cloud unlike every training cloud in a way the kept components cannot show.
  double residual = 0;
  Eigen::ArrayXd distance;  // to every reference (rows of stage.references), in the same space
};
StageScores decide_with_distances(const DecisionStage& stage, const Eigen::VectorXd& histogram, bool by_shape = false);
// decide_with_distances of the given rows of `histograms`, the same answers to the bit, computed a few
// queries per pass over the references (their sums held in registers), the passes shared among
// `threads` (0: all cores): visit(k, answer) for rows[k], each once, from any of the threads.
void decide_rows_with_distances(const DecisionStage& stage, const Eigen::MatrixXd& histograms,
                                const std::vector<Eigen::Index>& rows, int threads,
                                const std::function<void(size_t, StageScores&&)>& visit);

// Per category c, the mean over its objects[c] nearest training objects of the distance to each one's
// nearest reference (`distance` from decide_with_distances; `reference_object`: the training object of each
// reference). A category of fewer objects: over all of them. Empty when the sizes do not match.
Eigen::VectorXd nearest_objects_distance(const DecisionStage& stage, const Eigen::ArrayXd& distance,
                                         const std::vector<uint32_t>& reference_object, const std::vector<int>& objects);

int argmax(const Eigen::VectorXd& scores);  // ties: the lowest index

}  // namespace glimpse
