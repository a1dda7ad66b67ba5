#include "glimpse/learning/codebook.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <map>
#include <random>
#include <set>

namespace glimpse {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Standard normal from our own mapping of mt19937_64 (Box-Muller), reproducible on every platform.
struct Gauss {
  std::mt19937_64 rng;
  explicit Gauss(uint64_t seed) : rng(seed) {}
  double uniform() { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; }
  double operator()() { return std::sqrt(-2 * std::log(uniform())) * std::cos(2 * M_PI * uniform()); }
};

// n samples around each of the given centres (rows), with standard deviation sigma; truth = blob index.
MatrixXd blobs(const MatrixXd& centres, int per_blob, double sigma, uint64_t seed, std::vector<int>* truth) {
  Gauss g(seed);
  MatrixXd rows(centres.rows() * per_blob, centres.cols());
  for (int c = 0; c < centres.rows(); ++c)
    for (int i = 0; i < per_blob; ++i) {
      for (int j = 0; j < centres.cols(); ++j) rows(c * per_blob + i, j) = centres(c, j) + sigma * g();
      if (truth) truth->push_back(c);
    }
  return rows;
}

// ---- Standardiser

TEST(Standardiser, ZeroVarianceColumnGetsScaleOne) {
  MatrixXd rows(4, 3);
  rows << 1, 5, 10,  //
      2, 5, 20,      //
      3, 5, 30,      //
      4, 5, 40;
  const Standardiser s = fit_standardiser(rows);
  EXPECT_NEAR(s.mean[0], 2.5, 1e-12);
  EXPECT_NEAR(s.mean[1], 5.0, 1e-12);
  EXPECT_NEAR(s.scale[0], std::sqrt(1.25), 1e-12);  // population standard deviation
  EXPECT_EQ(s.scale[1], 1.0);
  const MatrixXd z = standardise(s, rows);
  for (int j : {0, 2}) {
    EXPECT_NEAR(z.col(j).mean(), 0.0, 1e-12);
    EXPECT_NEAR(z.col(j).squaredNorm() / 4, 1.0, 1e-12);
  }
  EXPECT_TRUE(z.col(1).isZero(0));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(standardise_row(s, rows.row(i).transpose()).isApprox(z.row(i).transpose()));
}

TEST(Standardiser, EmptyInputIsIdentity) {
  const Standardiser s = fit_standardiser(MatrixXd(0, 3));
  ASSERT_EQ(s.mean.size(), 3);
  EXPECT_TRUE(s.mean.isZero(0));
  EXPECT_TRUE(s.scale.isOnes(0));
}

// ---- PCA

TEST(Pca, FindsTheKnownPrincipalAxis) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 3).normalized();
  Gauss g(7);
  MatrixXd rows(500, 3);
  for (int i = 0; i < 500; ++i)
    rows.row(i) = (Eigen::Vector3d(4, 5, 6) + 10 * g() * axis + 0.1 * Eigen::Vector3d(g(), g(), g())).transpose();
  auto pca = fit_pca(rows, 0.9);
  ASSERT_TRUE(pca.ok()) << pca.error().message;
  ASSERT_EQ(pca->basis.cols(), 1);
  EXPECT_GT(pca->basis.col(0).dot(axis), 0.9999);  // sign convention: largest entry (3) positive
  EXPECT_GT(pca->explained[0], 0.99);
  EXPECT_NEAR(pca->mean[1], 5.0, 1.5);
}

TEST(Pca, ExplainedVarianceCutPicksTheCount) {
  // Independent columns with variances 100, 10, 1, 0.01: fractions 0.9, 0.09, 0.009, 0.00009.
  Gauss g(3);
  MatrixXd rows(4000, 4);
  const double sd[4] = {10, std::sqrt(10.0), 1, 0.1};
  for (int i = 0; i < rows.rows(); ++i)
    for (int j = 0; j < 4; ++j) rows(i, j) = sd[j] * g();
  const std::pair<double, int> cases[] = {{0.5, 1}, {0.8, 1}, {0.95, 2}, {0.998, 3}, {1.0, 4}};
  for (auto [fraction, expected] : cases) {
    auto pca = fit_pca(rows, fraction);
    ASSERT_TRUE(pca.ok());
    EXPECT_EQ(pca->basis.cols(), expected) << "explained_variance " << fraction;
    EXPECT_GE(pca->explained.sum(), std::min(fraction, 1.0) - 1e-9);
  }
  EXPECT_EQ(fit_pca(rows, 0.95, /*max_components=*/1)->basis.cols(), 1);
  EXPECT_EQ(fit_pca(rows, 0.5, -1, /*min_components=*/3)->basis.cols(), 3);
  // Orthonormal, ordered, signs fixed: the largest-magnitude entry of each column is positive.
  auto full = fit_pca(rows, 1.0);
  ASSERT_TRUE(full.ok());
  EXPECT_TRUE((full->basis.transpose() * full->basis).isIdentity(1e-9));
  for (int c = 0; c < 4; ++c) {
    Eigen::Index arg;
    full->basis.col(c).cwiseAbs().maxCoeff(&arg);
    EXPECT_GT(full->basis(arg, c), 0);
    if (c > 0) {
      EXPECT_GE(full->explained[c - 1], full->explained[c]);
    }
  }
}

TEST(Pca, FewerRowsThanDimensionsMatchesTheCovarianceReference) {
  // 40 sparse 600-bin histograms (counts of a few active bins), as Bag-of-Features vectors.
  std::mt19937_64 rng(11);
  MatrixXd rows = MatrixXd::Zero(40, 600);
  for (int i = 0; i < 40; ++i)
    for (int t = 0; t < 30; ++t) rows(i, (rng() % 60) * 10 + (i % 3)) += 1;
  auto pca = fit_pca(rows, 0.9);
  ASSERT_TRUE(pca.ok()) << pca.error().message;
  const int k = static_cast<int>(pca->basis.cols());
  ASSERT_GE(k, 2);
  ASSERT_LE(k, 39);  // never beyond the rank of 40 centred rows
  EXPECT_TRUE((pca->basis.transpose() * pca->basis).isIdentity(1e-9));

  // Brute-force reference: eigendecomposition of the 600 x 600 covariance.
  const MatrixXd centred = rows.rowwise() - rows.colwise().mean();
  Eigen::SelfAdjointEigenSolver<MatrixXd> eig(centred.transpose() * centred);
  const VectorXd values = eig.eigenvalues().reverse();
  const double total = values.sum();
  for (int c = 0; c < k; ++c) {
    EXPECT_NEAR(pca->explained[c], values[c] / total, 1e-9);
    if (c + 1 < k && values[c] - values[c + 1] > 1e-6 * total) {  // well-separated: same direction
      EXPECT_NEAR(std::abs(pca->basis.col(c).dot(eig.eigenvectors().col(599 - c))), 1.0, 1e-6);
    }
  }
  // Projection of rows agrees with the row variant and is centred.
  const MatrixXd z = project(*pca, rows);
  ASSERT_EQ(z.rows(), 40);
  ASSERT_EQ(z.cols(), k);
  EXPECT_TRUE(project_row(*pca, rows.row(5).transpose()).isApprox(z.row(5).transpose()));
  EXPECT_NEAR(z.col(0).mean(), 0.0, 1e-9);
  EXPECT_TRUE(project_row(*pca, pca->mean).isZero(1e-12));
}

// The scatter (or Gram) matrix's entries and the projected rows shared among threads: the same bits on
// one thread or several, and the same projection as one row at a time.
TEST(Pca, AnyThreadCountGivesTheSameBits) {
  Gauss g(11);
  for (auto [n, d] : {std::pair{300, 40}, std::pair{20, 60}}) {  // the covariance and the Gram paths
    MatrixXd rows(n, d);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < d; ++j) rows(i, j) = g() * (1.0 + j % 7) + (j % 3 == 0 && j > 0 ? 0.5 * rows(i, 0) : 0.0);
    auto one = fit_pca(rows, 0.95, -1, 1, 1);
    ASSERT_TRUE(one.ok()) << one.error().message;
    ASSERT_GT(one->basis.cols(), 1);
    const MatrixXd projected = project(*one, rows, 1);
    for (int threads : {2, 3, 0}) {
      auto shared = fit_pca(rows, 0.95, -1, 1, threads);
      ASSERT_TRUE(shared.ok());
      EXPECT_EQ(shared->mean, one->mean) << n << "x" << d << ", " << threads << " threads";
      EXPECT_EQ(shared->basis, one->basis) << n << "x" << d << ", " << threads << " threads";
      EXPECT_EQ(shared->explained, one->explained) << n << "x" << d << ", " << threads << " threads";
      EXPECT_EQ(project(*one, rows, threads), projected) << n << "x" << d << ", " << threads << " threads";
    }
    for (int i = 0; i < n; ++i)
      ASSERT_EQ(project_row(*one, rows.row(i).transpose()), projected.row(i).transpose()) << "row " << i;
  }
}

TEST(Pca, DegenerateInputIsAnError) {
  EXPECT_FALSE(fit_pca(MatrixXd(0, 5), 0.9).ok());
  EXPECT_FALSE(fit_pca(MatrixXd::Ones(1, 5), 0.9).ok());
  auto same = fit_pca(MatrixXd::Ones(10, 5), 0.9);
  ASSERT_FALSE(same.ok());
  EXPECT_EQ(same.error().code, ErrorCode::kInvalidArgument);
  MatrixXd nan = MatrixXd::Random(10, 3);
  nan(2, 1) = NAN;
  EXPECT_FALSE(fit_pca(nan, 0.9).ok());
  const MatrixXd good = MatrixXd::Random(10, 3);
  EXPECT_FALSE(fit_pca(good, 0.0).ok());
  EXPECT_FALSE(fit_pca(good, 1.5).ok());
  EXPECT_FALSE(fit_pca(good, 0.9, 0).ok());
  EXPECT_FALSE(fit_pca(good, 0.9, 2, 3).ok());
  EXPECT_TRUE(fit_pca(good, 0.9, 2, 2).ok());
}

TEST(Pca, RankCapsTheComponentCount) {
  MatrixXd rows(50, 4);  // every row on one line: rank 1
  for (int i = 0; i < 50; ++i) rows.row(i) << i, 2 * i, 0, -i;
  auto pca = fit_pca(rows, 1.0, -1, /*min_components=*/3);
  ASSERT_TRUE(pca.ok());
  EXPECT_EQ(pca->basis.cols(), 1);
  EXPECT_NEAR(pca->explained[0], 1.0, 1e-12);
}

// ---- k-means

MatrixXd blob_centres() {
  MatrixXd c(4, 3);
  c << 0, 0, 0,  //
      10, 0, 0,  //
      0, 10, 0,  //
      0, 0, 10;
  return c;
}

TEST(KMeans, FindsWellSeparatedBlobs) {
  std::vector<int> truth;
  const MatrixXd centres = blob_centres();
  const MatrixXd rows = blobs(centres, 100, 0.5, 5, &truth);
  auto r = kmeans(rows, {.k = 4, .seed = 3});
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->centres.rows(), 4);
  ASSERT_EQ(r->labels.size(), rows.rows());
  // Labels match the truth up to a permutation.
  std::map<int, int> to_found;
  for (size_t i = 0; i < truth.size(); ++i) {
    auto [it, inserted] = to_found.emplace(truth[i], r->labels[i]);
    EXPECT_EQ(it->second, r->labels[i]) << "row " << i;
  }
  std::set<int> used;
  for (auto [t, f] : to_found) used.insert(f);
  EXPECT_EQ(used.size(), 4u);
  for (auto [t, f] : to_found) EXPECT_LT((r->centres.row(f) - centres.row(t)).norm(), 0.3);
  // Inertia is the sum of squared distances to the assigned centres.
  double inertia = 0;
  for (Eigen::Index i = 0; i < rows.rows(); ++i) inertia += (rows.row(i) - r->centres.row(r->labels[i])).squaredNorm();
  EXPECT_NEAR(r->inertia, inertia, 1e-9 * inertia);
  EXPECT_NEAR(r->inertia / rows.rows(), 3 * 0.25, 0.15);
  EXPECT_GE(r->iterations, 1);
}

TEST(KMeans, DeterministicAcrossRunsAndThreads) {
  Gauss g(9);
  MatrixXd rows(6000, 8);
  for (Eigen::Index i = 0; i < rows.rows(); ++i)
    for (int j = 0; j < 8; ++j) rows(i, j) = g() + ((i % 7) * (j + 1) % 5);
  KMeansParams p{.k = 12, .restarts = 3, .seed = 42, .threads = 1};
  auto a = kmeans(rows, p);
  auto b = kmeans(rows, p);
  p.threads = 2;
  auto c = kmeans(rows, p);
  p.threads = 0;
  auto d = kmeans(rows, p);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok() && d.ok());
  for (const auto* other : {&b, &c, &d}) {
    EXPECT_EQ(a->centres, (*other)->centres);  // bit-identical
    EXPECT_EQ(a->labels, (*other)->labels);
    EXPECT_EQ(a->inertia, (*other)->inertia);
    EXPECT_EQ(a->iterations, (*other)->iterations);
  }
  p.seed = 43;
  auto e = kmeans(rows, p);
  ASSERT_TRUE(e.ok());
  EXPECT_NE(a->centres, e->centres);  // the seed matters
}

TEST(KMeans, RestartsNeverIncreaseAndSometimesLowerInertia) {
  // 12 blobs on a 4 x 3 grid, spacing close to their spread: single seedings often merge two.
  MatrixXd centres(12, 2);
  for (int i = 0; i < 12; ++i) centres.row(i) << (i % 4) * 3.0, (i / 4) * 3.0;
  const MatrixXd rows = blobs(centres, 40, 0.8, 21, nullptr);
  int strictly_better = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    auto one = kmeans(rows, {.k = 12, .restarts = 1, .seed = seed});
    auto many = kmeans(rows, {.k = 12, .restarts = 8, .seed = seed});
    ASSERT_TRUE(one.ok() && many.ok());
    EXPECT_LE(many->inertia, one->inertia);  // restart 0 is the single run
    strictly_better += many->inertia < one->inertia * (1 - 1e-9) ? 1 : 0;
  }
  EXPECT_GT(strictly_better, 0);
}

TEST(KMeans, KUpToTheDistinctRowCount) {
  MatrixXd base(5, 2);
  base << 0, 0, 1, 0, 0, 1, 5, 5, -3, 2;
  MatrixXd rows(20, 2);
  for (int i = 0; i < 20; ++i) rows.row(i) = base.row(i % 5);
  auto five = kmeans(rows, {.k = 5});
  ASSERT_TRUE(five.ok());
  EXPECT_EQ(five->inertia, 0.0);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(five->centres.row(five->labels[i]), rows.row(i));
  auto six = kmeans(rows, {.k = 6});
  ASSERT_FALSE(six.ok());
  EXPECT_EQ(six.error().code, ErrorCode::kInvalidArgument);
  auto one = kmeans(rows, {.k = 1});
  ASSERT_TRUE(one.ok());
  EXPECT_TRUE(one->centres.row(0).isApprox(rows.colwise().mean(), 1e-12));
}

TEST(KMeans, InvalidParametersAreErrors) {
  const MatrixXd rows = MatrixXd::Random(30, 2);
  EXPECT_FALSE(kmeans(MatrixXd(0, 2), {.k = 1}).ok());
  EXPECT_FALSE(kmeans(rows, {}).ok());  // k is required
  EXPECT_FALSE(kmeans(rows, {.k = 2, .restarts = 0}).ok());
  EXPECT_FALSE(kmeans(rows, {.k = 2, .max_iterations = 0}).ok());
  EXPECT_FALSE(kmeans(rows, {.k = 31}).ok());
  MatrixXd nan = rows;
  nan(3, 0) = INFINITY;
  EXPECT_FALSE(kmeans(nan, {.k = 2}).ok());
}

TEST(NearestCentre, L1AndL2CanDisagree) {
  MatrixXd centres(2, 2);
  centres << 3, 0,  //
      2, 2;         // L1: 3 vs 4; L2: 3 vs 2.83
  const VectorXd x = VectorXd::Zero(2);
  EXPECT_EQ(nearest_centre(centres, x), 1);
  EXPECT_EQ(nearest_centre(MatrixXd(0, 2), x), -1);
  MatrixXd tie(2, 1);
  tie << -1, 1;
  EXPECT_EQ(nearest_centre(tie, VectorXd::Zero(1)), 0);  // lowest index on ties
}

TEST(Assign, MatchesBruteForceForAnyThreadCount) {
  const MatrixXd centres = MatrixXd::Random(9, 5);
  const MatrixXd rows = MatrixXd::Random(3000, 5);
  for (int threads : {1, 2, 0}) {
    const std::vector<int> labels = assign(centres, rows, threads);
    ASSERT_EQ(labels.size(), 3000u);
    for (Eigen::Index i = 0; i < rows.rows(); ++i) {
      Eigen::Index best;
      (centres.rowwise() - rows.row(i)).rowwise().squaredNorm().minCoeff(&best);
      ASSERT_EQ(labels[i], best) << "row " << i << " threads " << threads;
    }
  }
  EXPECT_TRUE(assign(centres, MatrixXd(0, 5)).empty());
}

// ---- Distances

TEST(Distances, KnownValues) {
  VectorXd a(3), b(3);
  a << 1, 0, 2;
  b << 0, 0, 4;
  EXPECT_DOUBLE_EQ(l1(a, b), 3.0);
  EXPECT_DOUBLE_EQ(l1(a, a), 0.0);
  const Eigen::VectorXf af = a.cast<float>(), bf = b.cast<float>();
  EXPECT_DOUBLE_EQ(l1(af, bf), 3.0);
}

}  // namespace
}  // namespace glimpse
