// From keypoints to a category (sec. 3.2.5-3.3.3, 4): keypoint codebooks, the global histograms of
// the paper's methods (Bag of Keypoints, Bag of Graphs, KGH) and the Bag-of-Features decision stage.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "glimpse/codebook.h"
#include "glimpse/descriptor.h"
#include "glimpse/expected.h"
#include "glimpse/train_params.h"

namespace glimpse {

// ---- Keypoint codebook (sec. 3.2.5): standardise -> PCA -> K-means ------------------------------

struct KeypointCodebook {
  Standardiser standardiser;
  Pca pca;
  Eigen::MatrixXd centres;  // clusters x PCA dims
};

struct CodebookParams {
  int clusters = 60;
  double explained_variance = 0.95;
  int restarts = 4;
  uint64_t seed = 1;
  int threads = 0;
};

Expected<KeypointCodebook> fit_keypoint_codebook(const Eigen::MatrixXd& descriptors, const CodebookParams& params);
// The cluster ("word") of every descriptor.
std::vector<int> keypoint_words(const KeypointCodebook& codebook, const std::vector<Descriptor>& descriptors);
Eigen::MatrixXd descriptor_rows(const std::vector<Descriptor>& descriptors);

// ---- Bag of Keypoints (sec. 3.2.6) ----------------------------------------------------------------

// Histogram of keypoint words; divided by the keypoint count when `normalise` (sec. 4).
Eigen::VectorXd bag_of_keypoints(const std::vector<int>& words, int clusters, bool normalise);
// Soft words: each keypoint shares one count among its `spread` nearest codebook centres, in inverse
// proportion to its distance to each (spread 1: bag_of_keypoints of the hard words). A view of few
// keypoints then says more than which single cluster each fell in.
Eigen::VectorXd soft_bag_of_keypoints(const KeypointCodebook& codebook, const std::vector<Descriptor>& descriptors,
                                      int spread, bool normalise);

// ---- Bag of Graphs (sec. 3.2.6, Fig. 2) -----------------------------------------------------------

// A keypoint and its 3 nearest keypoints, the neighbours ordered by cluster number (not distance),
// with the volume of the tetrahedron of the 4 points.
struct LocalGraph {
  int centre = 0;
  std::array<int, 3> neighbours{};
  double volume = 0;  // m^3
};

double tetrahedron_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
// One graph per keypoint; none when there are fewer than 4 keypoints.
std::vector<LocalGraph> local_graphs(const std::vector<Vec3>& positions, const std::vector<int>& words);

// The graph types seen in training: volume clusters (1-D K-means of log10 volume) and the sorted list
// of type codes, each a histogram bin.
struct GraphVocabulary {
  int keypoint_clusters = 6;
  std::vector<double> log_volume_centres;  // ascending
  std::vector<uint64_t> types;             // ascending
};

int volume_cluster(const GraphVocabulary& vocabulary, double volume);
uint64_t graph_type(const GraphVocabulary& vocabulary, const LocalGraph& graph);
Expected<GraphVocabulary> fit_graph_vocabulary(const std::vector<std::vector<LocalGraph>>& graphs_per_cloud,
                                               int keypoint_clusters, int volume_clusters, uint64_t seed);
// Counts of each known graph type (unseen types are dropped); divided by the graph count when normalising.
Eigen::VectorXd bag_of_graphs(const std::vector<LocalGraph>& graphs, const GraphVocabulary& vocabulary, bool normalise);

// ---- KGH: keypoint-based global structure histogram (after Madry et al.'s GSH) --------------------

// Histogram over (word_i, word_j) pairs x distance bins in [0, max_distance_m] (the last bin takes
// everything beyond); paper: 8 clusters -> 64 x 15.
Eigen::VectorXd keypoint_global_histogram(const std::vector<Vec3>& positions, const std::vector<int>& words,
                                          int clusters, int distance_bins, float max_distance_m, bool normalise);

// ---- Bag of Features decision (sec. 3.3.2-3.3.3, 4) -----------------------------------------------

struct DecisionStage {
  DecisionRule kind = DecisionRule::kNearestNeighbours;
  int categories = 0;
  int neighbours = 5;
  Pca pca;                     // of the training histograms
  Eigen::MatrixXd references;  // centres or training vectors, in PCA space (rows)
  std::vector<int> labels;     // category of each reference
  double temperature = 1;      // L1 distance scale turning distances into scores (see fit_decision)
  bool projected = true;       // false: no PCA (the identity), references are histograms
};
// True when the stage's PCA is the identity (fit_decision without PCA; checked once on a read model).
bool is_identity_projection(const Pca& pca);

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

// Per category c, the mean over its objects[c] nearest training objects of the distance to each one's
// nearest reference (`distance` from decide_with_distances; `reference_object`: the training object of each
// reference). A category of fewer objects: over all of them. Empty when the sizes do not match.
Eigen::VectorXd nearest_objects_distance(const DecisionStage& stage, const Eigen::ArrayXd& distance,
                                         const std::vector<uint32_t>& reference_object, const std::vector<int>& objects);

int argmax(const Eigen::VectorXd& scores);  // ties: the lowest index

}  // namespace glimpse
