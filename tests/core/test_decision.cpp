// The decision stage: its rules on clear data, the nearest reference's temperature and novelty distances,
// and its batched distances (many queries per pass over the references, the same bits as one query at a
// time; the temperature over all training rows or an evenly spaced sample of them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "glimpse/learning/decision.h"

namespace glimpse {
namespace {

// 1500 histograms of 20 bins in 3 categories, 5 rows per object: more than one tile of references
// (512 rows) and a last pass of fewer than its 32 queries.
struct Rows {
  Eigen::MatrixXd h;
  std::vector<int> labels, objects;
};
Rows random_rows(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Rows r;
  r.h.resize(static_cast<Eigen::Index>(n), 20);
  for (size_t i = 0; i < n; ++i) {
    const int c = static_cast<int>(i % 3);
    for (Eigen::Index b = 0; b < 20; ++b) r.h(static_cast<Eigen::Index>(i), b) = u(rng) + (b / 7 == c ? 2.0 : 0.0);
    r.labels.push_back(c);
    r.objects.push_back(static_cast<int>(i / 5));
  }
  return r;
}

// The temperature as the comment of fit_decision defines it, one pair at a time: for each of m rows
// evenly spaced (row j n / m), its nearest row of another object (columns added in order); the median.
double temperature_pair_by_pair(const Eigen::MatrixXd& y, const std::vector<int>& objects, Eigen::Index m) {
  std::vector<double> nearest;
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Index i = k * y.rows() / m;
    double best = INFINITY;
    for (Eigen::Index j = 0; j < y.rows(); ++j) {
      if (objects[static_cast<size_t>(i)] == objects[static_cast<size_t>(j)]) continue;
      double d = 0;
      for (Eigen::Index c = 0; c < y.cols(); ++c) d += std::abs(y(j, c) - y(i, c));
      best = std::min(best, d);
    }
    nearest.push_back(best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
  return nearest[nearest.size() / 2];
}

TEST(DecisionStage, TemperatureAndManyQueriesAtOnceGiveTheBitsOfOneAtATime) {
  const Rows train = random_rows(1500, 7), test = random_rows(203, 8);
  for (DecisionRule kind : {DecisionRule::kNearestReference, DecisionRule::kNearestNeighbours}) {
    DecisionParams p;
    p.kind = kind;
    p.neighbours = 5;
    p.temperature_queries = 0;  // every row
    auto all = fit_decision(train.h, train.labels, 3, p, 1, 2, train.objects);
    ASSERT_TRUE(all.ok()) << all.error().message;
    EXPECT_EQ(all->temperature, temperature_pair_by_pair(all->references, train.objects, 1500));
    p.temperature_queries = 300;  // a fifth of the rows
    auto st = fit_decision(train.h, train.labels, 3, p, 1, 2, train.objects);
    ASSERT_TRUE(st.ok()) << st.error().message;
    ASSERT_TRUE(st->projected);
    EXPECT_EQ(st->temperature, temperature_pair_by_pair(st->references, train.objects, 300));
    EXPECT_NE(st->temperature, all->temperature);
    EXPECT_NEAR(st->temperature, all->temperature, 0.03 * all->temperature);  // the sample's median is the median
    auto one = fit_decision(train.h, train.labels, 3, p, 1, 1, train.objects);
    ASSERT_TRUE(one.ok());
    EXPECT_EQ(one->temperature, st->temperature);

    std::vector<Eigen::Index> rows;
    for (Eigen::Index r = test.h.rows() - 1; r >= 0; r -= 2) rows.push_back(r);  // any rows, any order
    for (int threads : {1, 2}) {
      std::vector<int> seen(rows.size(), 0);
      decide_rows_with_distances(*st, test.h, rows, threads, [&](size_t k, StageScores&& got) {
        ++seen[k];
        const StageScores want = decide_with_distances(*st, test.h.row(rows[k]).transpose());
        EXPECT_EQ(got.scores, want.scores) << "row " << rows[k];
        EXPECT_EQ(got.nearest_distance, want.nearest_distance);
        EXPECT_EQ(got.nearest_reference, want.nearest_reference);
        EXPECT_EQ(got.residual, want.residual);
        EXPECT_TRUE((got.distance == want.distance).all());
      });
      EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<std::ptrdiff_t>(rows.size())) << threads << " threads";
    }
  }
}

TEST(StreamDecision, NearestCentreAndNeighboursAgreeOnClearData) {
  Eigen::MatrixXd h(6, 3);
  h << 1, 0, 0, 0.9, 0.1, 0, 0, 1, 0, 0.1, 0.9, 0, 0, 0, 1, 0, 0.1, 0.9;
  const std::vector<int> labels = {0, 0, 1, 1, 2, 2};
  for (DecisionRule kind : {DecisionRule::kNearestCentre, DecisionRule::kCentres, DecisionRule::kNearestNeighbours}) {
    DecisionParams p;
    p.kind = kind;
    p.neighbours = 1;
    p.centres_per_category = 2;
    auto st = fit_decision(h, labels, 3, p, 1, 1);
    ASSERT_TRUE(st.ok()) << st.error().message;
    EXPECT_EQ(argmax(decide(*st, Eigen::Vector3d(0.95, 0.05, 0))), 0);
    EXPECT_EQ(argmax(decide(*st, Eigen::Vector3d(0.05, 0.95, 0))), 1);
    EXPECT_EQ(argmax(decide(*st, Eigen::Vector3d(0, 0.05, 0.95))), 2);
  }
  auto missing = fit_decision(h, {0, 0, 1, 1, 1, 1}, 3, {}, 1, 1);
  EXPECT_FALSE(missing.ok());
}

// The nearest-reference temperature: the median L1 distance from each training vector to its nearest
// vector of another object. Rows (0,0) (1,0) of object 0, (0,3) of object 1 (category 0), (5,5), (5,7)
// of objects 2 and 3 (category 1): nearest of another object 3, 4, 3, 2, 2 -> median 3; counting the
// same object's other view (no groups) 1, 1, 3, 2, 2 -> 2. The same on one thread or two.
TEST(DecisionStage, NearestReferenceTemperatureIsTheMedianDistanceToAnotherObject) {
  Eigen::MatrixXd h(5, 2);
  h << 0, 0, 1, 0, 0, 3, 5, 5, 5, 7;
  const std::vector<int> labels = {0, 0, 0, 1, 1}, groups = {0, 0, 1, 2, 3};
  DecisionParams p;
  p.kind = DecisionRule::kNearestReference;
  p.pca_explained_variance = 0;
  for (int threads : {1, 2}) {
    auto st = fit_decision(h, labels, 2, p, 1, threads, groups);
    ASSERT_TRUE(st.ok()) << st.error().message;
    EXPECT_DOUBLE_EQ(st->temperature, 3.0) << threads << " threads";
    EXPECT_EQ(argmax(decide(*st, Eigen::Vector2d(0.2, 0.5))), 0);
    EXPECT_EQ(argmax(decide(*st, Eigen::Vector2d(4, 6))), 1);
  }
  auto ungrouped = fit_decision(h, labels, 2, p, 1, 2);
  ASSERT_TRUE(ungrouped.ok());
  EXPECT_DOUBLE_EQ(ungrouped->temperature, 2.0);
}

// A cloud's distance to a category for its novelty: the mean over the category's k nearest training
// objects of the distance to each one's nearest reference. The same rows as above, objects 0 (two views),
// 1 (category 0), 2, 3 (category 1); the query (0, 1): L1 to the rows 1, 2, 2, 9, 11, so object 0 is at 1
// (its nearer view), object 1 at 2, objects 2 and 3 at 9 and 11. k = 1: 1 and 9 (the nearest reference);
// k = 2: 1.5 and 10; k = 5: all of each category's objects, the same; k per category.
TEST(DecisionStage, NoveltyDistanceIsTheMeanOverTheNearestObjects) {
  Eigen::MatrixXd h(5, 2);
  h << 0, 0, 1, 0, 0, 3, 5, 5, 5, 7;
  const std::vector<int> labels = {0, 0, 0, 1, 1};
  const std::vector<uint32_t> objects = {0, 0, 1, 2, 3};
  DecisionParams p;
  p.kind = DecisionRule::kNearestReference;
  p.pca_explained_variance = 0;
  auto st = fit_decision(h, labels, 2, p, 1, 1, {0, 0, 1, 2, 3});
  ASSERT_TRUE(st.ok()) << st.error().message;
  const StageScores s = decide_with_distances(*st, Eigen::Vector2d(0, 1));
  ASSERT_EQ(s.distance.size(), 5);
  EXPECT_DOUBLE_EQ(s.distance[4], 11.0);
  const Eigen::VectorXd one = nearest_objects_distance(*st, s.distance, objects, {1, 1});
  const Eigen::VectorXd two = nearest_objects_distance(*st, s.distance, objects, {2, 2});
  const Eigen::VectorXd all = nearest_objects_distance(*st, s.distance, objects, {5, 5});
  ASSERT_EQ(two.size(), 2);
  EXPECT_DOUBLE_EQ(one[0], s.nearest_distance[0]);
  EXPECT_DOUBLE_EQ(one[1], s.nearest_distance[1]);
  EXPECT_DOUBLE_EQ(two[0], 1.5);
  EXPECT_DOUBLE_EQ(two[1], 10.0);
  EXPECT_EQ(all, two);
  EXPECT_EQ(nearest_objects_distance(*st, s.distance, {0, 0, 1}, {2, 2}).size(), 0);  // objects of other references
  EXPECT_EQ(nearest_objects_distance(*st, s.distance, objects, {2}).size(), 0);       // a count per category
  const Eigen::VectorXd mixed = nearest_objects_distance(*st, s.distance, objects, {1, 2});
  EXPECT_DOUBLE_EQ(mixed[0], 1.0);
  EXPECT_DOUBLE_EQ(mixed[1], 10.0);
}

// sec. 4's rule: early in an exploration a view's few keypoints are compared by their proportions.
// Centres (21, 19, 0) (40 keypoints, words 0 and 1) and (0.5, 1.5, 10) (12 keypoints, word 2). A
// normalised few-keypoint view of words 0 and 1, (0.5, 0.5, 0): L1 by counts 39 vs 11 (the small
// category wins on mass alone); by shape, against (0.525, 0.475, 0) and (0.042, 0.125, 0.833): 0.05 vs 1.67.
TEST(StreamDecision, ByShapeComparesProportionsWithoutPca) {
  Eigen::MatrixXd h(4, 3);
  h << 20, 20, 0, 22, 18, 0, 1, 1, 10, 0, 2, 10;
  const std::vector<int> labels = {0, 0, 1, 1};
  DecisionParams p;
  p.kind = DecisionRule::kNearestCentre;
  p.pca_explained_variance = 0;  // no PCA: L1 on the histograms
  auto st = fit_decision(h, labels, 2, p, 1, 1);
  ASSERT_TRUE(st.ok()) << st.error().message;
  EXPECT_FALSE(st->projected);
  EXPECT_TRUE(is_identity_projection(st->pca));
  EXPECT_EQ(argmax(decide(*st, Eigen::Vector3d(21, 19, 0))), 0);
  const Eigen::Vector3d few(0.5, 0.5, 0);
  EXPECT_EQ(argmax(decide(*st, few)), 1);        // by counts: mass decides
  EXPECT_EQ(argmax(decide(*st, few, true)), 0);  // by shape: proportions decide
  // With PCA the flag changes nothing.
  p.pca_explained_variance = 0.98;
  auto projected = fit_decision(h, labels, 2, p, 1, 1);
  ASSERT_TRUE(projected.ok());
  EXPECT_TRUE(projected->projected);
  EXPECT_EQ(decide(*projected, few, true), decide(*projected, few));
}

}  // namespace
}  // namespace glimpse
