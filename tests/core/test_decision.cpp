// The decision stage's batched distances: many queries per pass over the references, the same bits as
// one query at a time; the temperature over all training rows or an evenly spaced sample of them.
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

}  // namespace
}  // namespace glimpse
