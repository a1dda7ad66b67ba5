// The paper's global histograms (classifiers.h): Bag of Keypoints with hard and soft words, Bag of
// Graphs' local graphs and vocabulary, the keypoint global histogram.
#include <gtest/gtest.h>

#include <vector>

#include "glimpse/learning/classifiers.h"

namespace glimpse {
namespace {

TEST(BagOfKeypoints, CountsAndNormalises) {
  const Eigen::VectorXd h = bag_of_keypoints({0, 2, 2, 1, 2}, 4, false);
  EXPECT_EQ(h, Eigen::Vector4d(1, 1, 3, 0));
  EXPECT_TRUE(bag_of_keypoints({0, 2, 2, 1, 2}, 4, true).isApprox(Eigen::Vector4d(0.2, 0.2, 0.6, 0)));
  EXPECT_EQ(bag_of_keypoints({}, 3, true), Eigen::Vector3d::Zero());
}

TEST(BagOfKeypoints, SoftWordsShareEachKeypointByInverseDistance) {
  // A codebook that reads the first two descriptor fields as they are: centres (0,0), (1,0), (0,3).
  KeypointCodebook cb;
  cb.standardiser.mean = Eigen::VectorXd::Zero(kDescriptorSize);
  cb.standardiser.scale = Eigen::VectorXd::Ones(kDescriptorSize);
  cb.pca.mean = Eigen::VectorXd::Zero(kDescriptorSize);
  cb.pca.basis = Eigen::MatrixXd::Zero(kDescriptorSize, 2);
  cb.pca.basis(0, 0) = cb.pca.basis(1, 1) = 1;
  cb.pca.explained = Eigen::Vector2d(0.5, 0.5);
  cb.centres.resize(3, 2);
  cb.centres << 0, 0, 1, 0, 0, 3;
  Descriptor a = Descriptor::Zero(), b = Descriptor::Zero();
  a[0] = 0.25f;  // 0.25 from centre 0, 0.75 from centre 1: weights 3/4 and 1/4 between them
  b[0] = 1;      // on centre 1
  const std::vector<Descriptor> ds = {a, b};
  const Eigen::VectorXd hard = soft_bag_of_keypoints(cb, ds, 1, false);
  EXPECT_EQ(hard, bag_of_keypoints(keypoint_words(cb, ds), 3, false));
  const Eigen::VectorXd soft = soft_bag_of_keypoints(cb, ds, 2, false);
  EXPECT_NEAR(soft[0], 0.75, 1e-6);
  EXPECT_NEAR(soft[1], 0.25 + 1.0, 1e-6);
  EXPECT_NEAR(soft[2], 0.0, 1e-12);
  EXPECT_NEAR(soft_bag_of_keypoints(cb, ds, 3, true).sum(), 1.0, 1e-9);  // normalised: one count per keypoint
}

TEST(BagOfGraphs, GraphsOrderNeighboursByClusterAndMeasureVolume) {
  const std::vector<Vec3> pos = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(5, 5, 5)};
  const std::vector<int> words = {0, 2, 1, 0, 1};
  const auto g = local_graphs(pos, words);
  ASSERT_EQ(g.size(), 5u);
  EXPECT_EQ(g[0].centre, 0);
  EXPECT_EQ(g[0].neighbours, (std::array<int, 3>{0, 1, 2}));
  EXPECT_NEAR(g[0].volume, 1.0 / 6.0, 1e-9);
  EXPECT_TRUE(local_graphs({pos[0], pos[1], pos[2]}, {0, 1, 2}).empty());
  EXPECT_NEAR(tetrahedron_volume(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2)), 8.0 / 6.0, 1e-9);
}

TEST(BagOfGraphs, VocabularyCountsKnownTypesOnly) {
  std::vector<std::vector<LocalGraph>> train_graphs = {{{0, {0, 1, 1}, 1e-3}, {1, {0, 0, 1}, 1e-6}},
                                                       {{1, {0, 0, 1}, 2e-6}, {0, {1, 1, 1}, 2e-3}}};
  auto voc = fit_graph_vocabulary(train_graphs, 2, 2, 1);
  ASSERT_TRUE(voc.ok()) << voc.error().message;
  EXPECT_EQ(voc->types.size(), 3u);
  EXPECT_NE(volume_cluster(*voc, 1e-3), volume_cluster(*voc, 1e-6));
  const Eigen::VectorXd h = bag_of_graphs({{1, {0, 0, 1}, 1.5e-6}, {0, {0, 0, 0}, 1e-3}}, *voc, false);
  EXPECT_EQ(h.sum(), 1.0) << "the unseen type is dropped";
}

TEST(KeypointGlobalHistogram, SymmetricPairsByDistance) {
  const std::vector<Vec3> pos = {Vec3(0, 0, 0), Vec3(0.1f, 0, 0), Vec3(0.9f, 0, 0)};
  const Eigen::VectorXd h = keypoint_global_histogram(pos, {0, 1, 1}, 2, 4, 1.0f, false);
  ASSERT_EQ(h.size(), 16);
  EXPECT_EQ(h.sum(), 6);
  EXPECT_EQ(h[(0 * 2 + 1) * 4 + 0], 1);  // (0,1) at 0.1
  EXPECT_EQ(h[(1 * 2 + 0) * 4 + 0], 1);
  EXPECT_EQ(h[(0 * 2 + 1) * 4 + 3], 1);  // (0,1) at 0.9
  EXPECT_EQ(h[(1 * 2 + 1) * 4 + 3], 2);  // (1,1) at 0.8
}

}  // namespace
}  // namespace glimpse
