// The fusion's logistic decision (chi2_logistic.h): the feature map against the kernel it approximates,
// the fit against data whose answer is known, and its place in a trained model (calibrated share, bytes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "format3.h"
#include "glimpse/learning/chi2_logistic.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/scores.h"
#include "glimpse/random.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/features/upright_histogram.h"
#include "glimpse/features/global_descriptors.h"
#include "synthetic.h"

namespace glimpse {
namespace {

Eigen::VectorXd random_histogram(std::mt19937& rng, int bins, double zeros) {
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::VectorXd h(bins);
  for (int i = 0; i < bins; ++i) h[i] = u(rng) < zeros ? 0 : u(rng);
  return h;
}

// The additive chi2 kernel of two unit-mass histograms: sum 2 x y / (x + y).
double chi2_kernel(Eigen::VectorXd x, Eigen::VectorXd y) {
  x /= x.sum(), y /= y.sum();
  double k = 0;
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (x[i] + y[i] > 0) k += 2 * x[i] * y[i] / (x[i] + y[i]);
  return k;
}

TEST(AdditiveChi2Map, DotProductsApproximateTheKernel) {
  std::mt19937 rng(7);
  double worst2 = 0, worst3 = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd x = random_histogram(rng, 40, 0.3), y = random_histogram(rng, 40, 0.3);
    const double k = chi2_kernel(x, y);
    ASSERT_GT(k, 0.1);
    worst2 = std::max(worst2, std::abs(additive_chi2_features({x}, 2, 0.5).dot(additive_chi2_features({y}, 2, 0.5)) - k) / k);
    worst3 = std::max(worst3, std::abs(additive_chi2_features({x}, 3, 0.5).dot(additive_chi2_features({y}, 3, 0.5)) - k) / k);
  }
  EXPECT_LT(worst2, 0.1);    // measured 0.083 (scikit-learn's AdditiveChi2Sampler: 0.089 on such draws)
  EXPECT_LT(worst3, 0.012);  // more terms, closer
  EXPECT_LT(worst3, worst2);
  // A histogram with itself: its mass, 1.
  const Eigen::VectorXd x = random_histogram(rng, 40, 0.3);
  EXPECT_NEAR(additive_chi2_features({x}, 3, 0.5).squaredNorm(), 1.0, 0.02);  // measured 0.985
}

TEST(AdditiveChi2Map, LayoutScaleAndEmptyHistograms) {
  std::mt19937 rng(3);
  const Eigen::VectorXd a = random_histogram(rng, 10, 0.2), b = random_histogram(rng, 6, 0.2);
  const Eigen::VectorXd f = additive_chi2_features({a, b}, 2, 0.5);
  ASSERT_EQ(f.size(), 3 * 10 + 3 * 6);
  // Each histogram mapped on its own (so a method's bins do not outweigh another's), in order.
  EXPECT_TRUE(f.head(30).isApprox(additive_chi2_features({a}, 2, 0.5)));
  EXPECT_TRUE(f.tail(18).isApprox(additive_chi2_features({b}, 2, 0.5)));
  // Mass does not count: the histogram's proportions do.
  EXPECT_TRUE(additive_chi2_features({a * 7.0}, 2, 0.5).isApprox(additive_chi2_features({a}, 2, 0.5)));
  // No mass, or only negative bins: zeros, not NaN.
  const Eigen::VectorXd none = additive_chi2_features({Eigen::VectorXd::Zero(5), -a}, 2, 0.5);
  ASSERT_EQ(none.size(), 15 + 30);
  EXPECT_TRUE(none.isZero());
}

// Three categories, each a histogram peaked in its own third: the logistic decision learns them.
struct Toy {
  Eigen::MatrixXd features;
  std::vector<int> labels;
};
Toy toy(int per_category, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Eigen::VectorXd> rows;
  Toy t;
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < per_category; ++i) {
      Eigen::VectorXd h = random_histogram(rng, 30, 0.5);
      h.segment(10 * c, 10) *= 8;
      rows.push_back(additive_chi2_features({h}, 2, 0.5));
      t.labels.push_back(c);
    }
  t.features.resize(static_cast<Eigen::Index>(rows.size()), rows.front().size());
  for (size_t r = 0; r < rows.size(); ++r) t.features.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
  return t;
}

TEST(Chi2Logistic, LearnsSeparableCategoriesAndGivesADistribution) {
  const Toy train = toy(30, 1), test = toy(20, 2);
  auto head = fit_chi2_logistic(train.features, train.labels, 3, {});
  ASSERT_TRUE(head.ok()) << head.error().message;
  ASSERT_EQ(head->weights.rows(), 3);
  ASSERT_EQ(head->weights.cols(), train.features.cols());
  int right = 0;
  for (Eigen::Index r = 0; r < test.features.rows(); ++r) {
    const Eigen::VectorXd p = chi2_logistic_probabilities(*head, test.features.row(r).transpose());
    ASSERT_EQ(p.size(), 3);
    EXPECT_NEAR(p.sum(), 1.0, 1e-12);
    EXPECT_TRUE((p.array() > 0).all());
    int best = 0;
    for (int k = 1; k < 3; ++k)
      if (p[k] > p[best]) best = k;
    right += best == test.labels[static_cast<size_t>(r)];
  }
  EXPECT_GE(right, 57);  // of 60; measured 58
  // Deterministic: the same rows give the same weights.
  auto again = fit_chi2_logistic(train.features, train.labels, 3, {});
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->weights, head->weights);
  EXPECT_EQ(again->bias, head->bias);
  // The categories' problems shared among threads: the same weights on one thread or all.
  for (int threads : {2, 0}) {
    auto shared = fit_chi2_logistic(train.features, train.labels, 3, {}, threads);
    ASSERT_TRUE(shared.ok());
    EXPECT_EQ(shared->weights, head->weights) << threads << " threads";
    EXPECT_EQ(shared->bias, head->bias);
  }
  // A feature vector of another length is no answer, not a wrong one.
  EXPECT_EQ(chi2_logistic_probabilities(*head, Eigen::VectorXd::Zero(5)).size(), 0);
}

// Rows past one block of the sparse problem's fill (256): every row read as given, on any thread
// count. The same rows in reverse order are the same problem, summed in another order.
TEST(Chi2Logistic, ManyRowsAreReadAsGivenOnAnyThreadCount) {
  const Toy train = toy(250, 5), test = toy(20, 2);
  ASSERT_GT(train.features.rows(), 2 * 256);
  auto one = fit_chi2_logistic(train.features, train.labels, 3, {}, 1);
  ASSERT_TRUE(one.ok()) << one.error().message;
  for (int threads : {2, 3, 0}) {
    auto shared = fit_chi2_logistic(train.features, train.labels, 3, {}, threads);
    ASSERT_TRUE(shared.ok());
    EXPECT_EQ(shared->weights, one->weights) << threads << " threads";
    EXPECT_EQ(shared->bias, one->bias) << threads << " threads";
  }
  const Eigen::MatrixXd reversed = train.features.colwise().reverse();
  const std::vector<int> reversed_labels(train.labels.rbegin(), train.labels.rend());
  auto back = fit_chi2_logistic(reversed, reversed_labels, 3, {}, 2);
  ASSERT_TRUE(back.ok());
  EXPECT_LT((back->weights - one->weights).norm(), 1e-3 * one->weights.norm());
  int right = 0;
  for (Eigen::Index r = 0; r < test.features.rows(); ++r) {
    const Eigen::VectorXd p = chi2_logistic_probabilities(*one, test.features.row(r).transpose());
    const Eigen::VectorXd q = chi2_logistic_probabilities(*back, test.features.row(r).transpose());
    Eigen::Index best = 0, best_back = 0;
    p.maxCoeff(&best), q.maxCoeff(&best_back);
    EXPECT_EQ(best, best_back) << "test row " << r;
    right += best == test.labels[static_cast<size_t>(r)];
  }
  EXPECT_GE(right, 57);  // of 60
}

TEST(Chi2Logistic, TwoCategoriesGetOppositeWeights) {
  Toy t = toy(20, 4);
  std::vector<int> keep;
  for (size_t i = 0; i < t.labels.size(); ++i)
    if (t.labels[i] < 2) keep.push_back(static_cast<int>(i));
  Eigen::MatrixXd x(static_cast<Eigen::Index>(keep.size()), t.features.cols());
  std::vector<int> y;
  for (size_t i = 0; i < keep.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = t.features.row(keep[i]), y.push_back(t.labels[static_cast<size_t>(keep[i])]);
  auto head = fit_chi2_logistic(x, y, 2, {});
  ASSERT_TRUE(head.ok()) << head.error().message;
  EXPECT_TRUE(head->weights.row(0).isApprox(-head->weights.row(1)));
  const Eigen::VectorXd p = chi2_logistic_probabilities(*head, x.row(0).transpose());
  EXPECT_GT(p[y[0]], 0.5);
}

TEST(Chi2Logistic, Errors) {
  const Toy t = toy(5, 5);
  EXPECT_FALSE(fit_chi2_logistic(t.features, t.labels, 1, {}).ok());  // one category
  EXPECT_FALSE(fit_chi2_logistic(t.features, t.labels, 4, {}).ok());  // a category with no row
  EXPECT_FALSE(fit_chi2_logistic(t.features, std::vector<int>(3, 0), 3, {}).ok());  // rows and labels differ
  Chi2LogisticParams zero;
  zero.c = 0;
  EXPECT_FALSE(fit_chi2_logistic(t.features, t.labels, 3, zero).ok());
  Chi2LogisticParams no_tolerance;
  no_tolerance.tolerance = 0;
  EXPECT_FALSE(fit_chi2_logistic(t.features, t.labels, 3, no_tolerance).ok());
  std::vector<int> bad = t.labels;
  bad[0] = 9;
  EXPECT_FALSE(fit_chi2_logistic(t.features, bad, 3, {}).ok());
}

// ---- in a trained model --------------------------------------------------------------------------

TrainParams fusion_params(double c) {
  TrainParams p;
  p.methods = {MethodId::kUSH, MethodId::kVFH, MethodId::kFusion};
  p.fusion_head.c = c;
  return p;
}

struct Pair {
  Model with, without;
  std::vector<TrainingCloud> test;
};
const Pair& models() {
  static const Pair p = [] {
    const std::vector<TrainingCloud> data = test::synthetic_views(6, 3, 1);
    auto with = train(data, fusion_params(10)), without = train(data, fusion_params(0));
    EXPECT_TRUE(with.ok() && without.ok());
    return Pair{with.ok() ? *with : Model{}, without.ok() ? *without : Model{}, test::synthetic_views(3, 2, 2)};
  }();
  return p;
}

// The head's block at the end of a format-7 payload (serialize_impl.cpp): flag, steps, interval, weights
// (rows, cols, values), bias (size, values), share.
size_t head_block_bytes(size_t categories) {
  const size_t features = 3 * static_cast<size_t>(kUprightHistogramSize + kVfhSize);
  return 1 + 4 + 8 + (8 + 8 * categories * features) + (4 + 8 * categories) + 8;
}

TEST(FusionHead, ItsShareIsCalibratedOnHeldOutFoldsAndItMovesTheScores) {
  const Pair& p = models();
  ASSERT_FALSE(p.with.categories.empty());
  const Calibration& c = calibration(p.with);
  const std::vector<double> grid = fusion_params(10).fusion_head_shares;
  EXPECT_NE(std::find(grid.begin(), grid.end(), c.fusion_head_share), grid.end()) << c.fusion_head_share;
  EXPECT_EQ(calibration(p.without).fusion_head_share, 0.0);
  EXPECT_GT(c.held_out, 0u);
  // The stages are the same: where the head has a share, the scores move; where both shares are 0, not.
  size_t moved = 0;
  for (const TrainingCloud& t : p.test) {
    auto a = classify(p.with, t.cloud), b = classify(p.without, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    double sum = 0;
    for (double s : a->scores) sum += s;
    EXPECT_NEAR(sum, 1.0, 1e-9);
    moved += a->scores != b->scores;
  }
  if (c.fusion_head_share > 0) EXPECT_GT(moved, 0u);
  else EXPECT_EQ(moved, 0u);
  // A component method alone has no head.
  auto ush = classify(p.with, p.test.front().cloud, MethodId::kUSH), ush0 = classify(p.without, p.test.front().cloud, MethodId::kUSH);
  ASSERT_TRUE(ush.ok() && ush0.ok());
  EXPECT_EQ(ush->scores, ush0->scores);
}

TEST(FusionHead, LearnsAtMostItsRowsPerCategoryTheSameOnesEveryTime) {
  const std::vector<int> labels = {0, 1, 0, 0, 1, 0, 0, 2, 0, 0, 1, 0};  // 8, 3 and 1 rows
  std::vector<uint64_t> keys;
  for (size_t i = 0; i < labels.size(); ++i) keys.push_back(1000 + 17 * i);
  auto count = [&](const std::vector<uint8_t>& learns, int category) {
    int n = 0;
    for (size_t i = 0; i < labels.size(); ++i) n += learns[i] && labels[i] == category;
    return n;
  };
  const std::vector<uint8_t> capped = fusion_head_learns(labels, keys, 3, 2, 7);
  EXPECT_EQ(count(capped, 0), 2);
  EXPECT_EQ(count(capped, 1), 2);
  EXPECT_EQ(count(capped, 2), 1);  // fewer than the cap: all
  EXPECT_EQ(fusion_head_learns(labels, keys, 3, 2, 7), capped);
  EXPECT_NE(fusion_head_learns(labels, keys, 3, 2, 8), capped);  // another seed, other rows
  const std::vector<uint8_t> all = fusion_head_learns(labels, keys, 3, 0, 7);
  EXPECT_EQ(count(all, 0) + count(all, 1) + count(all, 2), int(labels.size()));
}

TEST(FusionHead, ARowIsLearntOrNotByItsKeyWhereverItStands) {
  // Rows of category 0 with a category-1 row put before them: the same rows of 0 are learnt.
  const std::vector<int> labels = {0, 0, 0, 0, 0, 0, 0, 0};
  std::vector<uint64_t> keys;
  for (size_t i = 0; i < labels.size(); ++i) keys.push_back(splitmix64(99, i));
  const std::vector<uint8_t> alone = fusion_head_learns(labels, keys, 2, 3, 7);
  std::vector<int> more_labels = {1};
  std::vector<uint64_t> more_keys = {12345};
  more_labels.insert(more_labels.end(), labels.begin(), labels.end());
  more_keys.insert(more_keys.end(), keys.begin(), keys.end());
  const std::vector<uint8_t> joined = fusion_head_learns(more_labels, more_keys, 2, 3, 7);
  EXPECT_EQ(std::vector<uint8_t>(joined.begin() + 1, joined.end()), alone);
  EXPECT_EQ(joined[0], 1);
}

TEST(FusionHead, TheModelBytesKeepItAndAFormat6ModelReadsWithoutIt) {
  const Pair& p = models();
  // The bytes as format 7 wrote them (format 8 ends with the novelty model's flag, 0: nothing augmented).
  const std::vector<uint8_t> current = serialize(p.with);
  const std::vector<uint8_t> bytes = test::as_format_7(test::format_11_bytes(p.with)),
                             plain = test::as_format_7(test::format_11_bytes(p.without));
  ASSERT_FALSE(bytes.empty());
  const size_t block = head_block_bytes(p.with.categories.size());
  ASSERT_EQ(bytes.size(), plain.size() + block - 1);  // the model without a head writes its flag alone
  auto back = deserialize(current);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(calibration(*back).fusion_head_share, calibration(p.with).fusion_head_share);
  for (const TrainingCloud& t : p.test) {
    auto a = classify(p.with, t.cloud), b = classify(*back, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
  }
  // Format 6: no head block. It reads, with no head: the mean of the components, as the model trained without.
  std::vector<uint8_t> six = bytes;
  six.erase(six.end() - 4 - static_cast<std::ptrdiff_t>(block), six.end() - 4);
  auto old = deserialize(test::with_version(six, 6, six.size() - 24));
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_EQ(calibration(*old).fusion_head_share, 0.0);
  for (const TrainingCloud& t : p.test) {
    auto a = classify(*old, t.cloud), b = classify(p.without, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
  }
  // A head that does not fit the model (another number of map steps: other feature counts) is refused.
  std::vector<uint8_t> odd = bytes;
  const size_t steps_at = odd.size() - 4 - block + 1;
  const int32_t three = 3;
  std::memcpy(odd.data() + steps_at, &three, 4);
  auto refused = deserialize(test::with_version(odd, 7, odd.size() - 24));
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("fusion logistic decision"), std::string::npos) << refused.error().message;
  // A share outside [0, 1] too.
  std::vector<uint8_t> share = bytes;
  const double two = 2;
  std::memcpy(share.data() + share.size() - 4 - 8, &two, 8);
  EXPECT_FALSE(deserialize(test::with_version(share, 7, share.size() - 24)).ok());
}

}  // namespace
}  // namespace glimpse
