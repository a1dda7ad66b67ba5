// From keypoints to a cloud's histogram (sec. 3.2.5-3.2.6): keypoint codebooks and the global histograms
// of the paper's methods (Bag of Keypoints, Bag of Graphs, KGH). The decision stage comparing histograms
// is decision.h.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "glimpse/learning/codebook.h"
#include "glimpse/features/descriptor.h"
#include "glimpse/expected.h"
#include "glimpse/learning/train_params.h"

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

}  // namespace glimpse
